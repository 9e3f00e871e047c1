//! `aras export-mjcf`: the robot of a parameter file as a MuJoCo model
//! (`docs/mjcf.md`).

use anyhow::{Context, Result};
use aras_dyn::Params;
use aras_dyn::mjcf::{MjcfOptions, to_mjcf, unrepresented};

use crate::cli::ExportMjcfArgs;
use crate::output::{FileKind, NewFile};
use crate::robot::{ParamsUse, read_params};

/// Runs `export-mjcf`: refuses an existing `--out` unless `--force` and it
/// is an MJCF this command wrote (never the parameter file itself), writes
/// the MJCF atomically and names the effects MuJoCo cannot express.
pub fn run(args: &ExportMjcfArgs) -> Result<()> {
    let loaded = super::load_config(&args.common)?;
    let out = NewFile::create(
        &args.out,
        args.common.force,
        FileKind::Mjcf,
        &super::input_files(&args.common, &loaded, &[&args.params]),
    )?;
    let params = read_params(
        &args.params,
        ParamsUse::Physical("MuJoCo simulates real bodies"),
    )?;
    let xml = to_mjcf(&params, &MjcfOptions::default())
        .with_context(|| format!("exporting {} to MJCF", args.params.display()))?;
    out.write(xml.as_bytes())?;
    out.commit()?;
    println!(
        "{}: MuJoCo model (MJCF) of {}",
        args.out.display(),
        args.params.display()
    );
    for u in unrepresented(&params) {
        eprintln!(
            "note: effect `{}` is not represented in MJCF ({}); listed in the XML comment",
            u.effect, u.why
        );
    }
    Ok(())
}

/// Writes `robot.xml` (the MJCF of `params`, the physically consistent
/// estimate) into a run's directory beside `params.json`. A parameter set
/// MuJoCo would reject is reported on stderr and no file is written: the
/// identification's other outputs stay valid.
pub fn write_beside(out: &crate::output::OutDir, params: &Params) -> Result<()> {
    match to_mjcf(params, &MjcfOptions::default()) {
        Ok(xml) => {
            out.write("robot.xml", xml)?;
        }
        Err(e) => eprintln!(
            "warning: robot.xml not written: {:#}",
            anyhow::Error::from(e)
        ),
    }
    Ok(())
}
