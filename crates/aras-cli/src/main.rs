//! `aras`: the ARAS-Diamond toolkit's command-line tools (run through `cargo xtask`).

use std::process::ExitCode;

use aras_cli::cli::{Cli, Command};
use aras_cli::cmd;
use clap::Parser;

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Ctrl-C / SIGTERM: remove this run's staging directories and locks
    // (finished outputs are untouched), then exit as interrupted.
    let _ = ctrlc::set_handler(|| {
        aras_cli::output::clean_up_interrupted();
        eprintln!("interrupted: nothing was replaced");
        std::process::exit(130);
    });
    let result = match &cli.command {
        Command::Pipeline(a) => cmd::pipeline::run(a),
        Command::Excite(a) => cmd::excite::run(a),
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::Identify(a) => cmd::identify::run(a),
        Command::Validate(a) => cmd::validate::run(a),
        Command::Predict(a) => cmd::predict::run(a),
        Command::Diagnose(a) => cmd::diagnose::run(a),
        Command::ExportMjcf(a) => cmd::export_mjcf::run(a),
        Command::Friction(a) => cmd::friction::run(a),
        Command::FrictionPredict(a) => cmd::friction::predict(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}
