//! Configuration errors name the file, the key and the line.

use aras_cli::config::{Config, Format};

fn err(text: &str, format: Format) -> String {
    Config::parse(text, format, "cfg")
        .expect_err("must be rejected")
        .to_string()
}

#[test]
fn unknown_toml_key_is_named_with_its_line() {
    let e = err("[signal]\nfilter_order = 4\ncutof_hz = 5.0\n", Format::Toml);
    assert!(e.starts_with("cfg:3:"), "{e}");
    assert!(
        e.contains("`signal.cutof_hz`") && e.contains("unknown field"),
        "{e}"
    );
}

#[test]
fn wrong_type_is_named() {
    let e = err("[simulation]\nperiods = \"many\"\n", Format::Toml);
    assert!(
        e.contains("`simulation.periods`") && e.starts_with("cfg:2:"),
        "{e}"
    );
}

#[test]
fn invalid_values_name_key_and_line() {
    let e = err("[identification.sdp]\nmass_tolerance = 1.5\n", Format::Toml);
    assert!(
        e.contains("cfg:2") && e.contains("`identification.sdp.mass_tolerance`"),
        "{e}"
    );
    // A validation frequency too close to a fixed cut-off; with the
    // data-chosen bandwidth the band follows the motion.
    let fast = "[validation]\nfrequencies_hz = [0.5, 8.0]\n";
    let e = err(
        &format!("[signal]\nbandwidth = \"fixed\"\n{fast}"),
        Format::Toml,
    );
    assert!(
        e.contains("`validation.frequencies_hz`") && e.contains("cut-off"),
        "{e}"
    );
    let auto = format!("[signal]\nbandwidth = \"auto\"\n{fast}");
    assert!(Config::parse(&auto, Format::Toml, "cfg").is_ok());
    let e = err("[robot]\nalpha_deg = 190.0\n", Format::Toml);
    assert!(e.contains("`robot.alpha_deg`"), "{e}");
}

#[test]
fn json_errors_name_the_key() {
    let e = err(
        "{\n  \"signal\": {\n    \"cutoff_hz\": 5,\n    \"oops\": 1\n  }\n}\n",
        Format::Json,
    );
    assert!(e.contains("`signal.oops`") && e.contains("cfg:4"), "{e}");
    let e = err("{\"trajectory\": {\"harmonics\": 0}}", Format::Json);
    assert!(e.contains("`trajectory.harmonics`"), "{e}");
    let ok = Config::parse("{\"signal\": {\"cutoff_hz\": 5}}", Format::Json, "cfg").unwrap();
    assert_eq!(ok.signal.cutoff_hz, 5.0);
}

#[test]
fn unknown_extension_is_refused() {
    let p = std::env::temp_dir().join(format!("aras-cfg-{}.yaml", std::process::id()));
    std::fs::write(&p, "x").unwrap();
    let e = Config::load(&p).unwrap_err().to_string();
    assert!(e.contains(".toml or .json"), "{e}");
    let _ = std::fs::remove_file(&p);
}
