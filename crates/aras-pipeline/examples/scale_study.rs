//! Scale study: time and peak memory of streaming identification
//! against log length. See `docs/scale.md`.
//!
//! ```text
//! scale_study write LOG.csv SECONDS RATE_HZ   # synthetic log with logged derivatives
//! scale_study identify LOG.csv [filtered]     # streaming OLS; prints samples, time, rate
//! ```
//! Run `identify` under `/usr/bin/time -v` for the peak memory (max RSS).

use std::path::Path;
use std::time::Instant;

use aras_dyn::Params;
use aras_ident::BaseParameters;
use aras_pipeline::robot::stack;
use aras_pipeline::streaming::{StreamingOptions, identify_log, synthetic};
use aras_signal::{Bandwidth, FilterSpec, PeriodSource};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: scale_study write LOG.csv SECONDS RATE_HZ | identify LOG.csv [filtered]";
    let p = Params::aras_diamond();
    let model = p.model()?;
    let geo = p.geometry()?;
    let beta = p.standard_vector(&model)?.as_slice().to_vec();
    match args.get(1).map(String::as_str) {
        Some("write") if args.len() == 5 => {
            let (secs, fs): (f64, f64) = (args[3].parse()?, args[4].parse()?);
            let n = (secs * fs).round() as usize;
            let t0 = Instant::now();
            synthetic::write_log(Path::new(&args[2]), &model, &geo, &beta, n, fs, 0.002)?;
            println!("wrote {n} samples in {:.1} s", t0.elapsed().as_secs_f64());
        }
        Some("identify") if args.len() >= 3 => {
            let rich = synthetic::states(&model, &geo, &beta, 2000, 200.0, 0.0)?;
            let samples = aras_signal::Samples {
                t: (0..2000).map(|i| i as f64 / 200.0).collect(),
                x: rich[0].to_vec(),
                x_dot: rich[1].to_vec(),
                x_ddot: rich[2].to_vec(),
                tau: rich[3].to_vec(),
                ..Default::default()
            };
            let st = stack(&model, &geo, &samples)?;
            let base = BaseParameters::from_regressor(st.w.as_ref(), &st.names, 1e-8)?;
            let mut o = StreamingOptions::default();
            o.process.period = PeriodSource::Off;
            if args.get(3).map(String::as_str) == Some("filtered") {
                o.process.filter = Bandwidth::Fixed(FilterSpec::default());
            } else {
                o.process.filter = Bandwidth::Off;
                o.process.use_logged_derivatives = true;
            }
            let t0 = Instant::now();
            let r = identify_log(Path::new(&args[2]), &model, &base, &o)?;
            let dt = t0.elapsed().as_secs_f64();
            println!(
                "route {:?}: {} samples read, {} used, {} blocks, {:.2} s, {:.2} M samples/s, residual std {:.4} N·m",
                r.route,
                r.samples_read,
                r.samples_used,
                r.blocks,
                dt,
                r.samples_read as f64 / dt / 1e6,
                r.ols.residual_variance.sqrt()
            );
        }
        _ => return Err(usage.into()),
    }
    Ok(())
}
