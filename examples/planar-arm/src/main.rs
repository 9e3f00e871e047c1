//! Runs the planar-arm example and prints what it found (see the library's
//! documentation).

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let o = planar_arm::run(&planar_arm::Settings::default())?;
    println!("excitation: κ = {:.1}", o.condition_number);
    println!("processing: {}", o.bandwidth);
    println!("largest q̈ error: {:.2e} rad/s²", o.max_accel_error);
    println!(
        "{:<40} {:>12} {:>12} {:>12}",
        "base parameter", "truth", "OLS", "SDP"
    );
    for i in 0..o.truth.len() {
        println!(
            "{:<40} {:>12.6} {:>12.6} {:>12.6}",
            o.base_names[i], o.truth[i], o.ols[i], o.sdp[i]
        );
    }
    println!(
        "SDP status {}, pseudo-inertia min eigenvalues {:?}",
        o.sdp_status, o.min_eigenvalues
    );
    let c = planar_arm::chain::identify(&planar_arm::chain::Chain::three_links(), 2000)?;
    let worst = |e: &[f64]| {
        e.iter()
            .zip(&c.truth)
            .map(|(e, t)| (e - t).abs() / t.abs())
            .fold(0.0, f64::max)
    };
    println!(
        "3-link chain: excitation κ = {:.1} (random feasible median {:.1}); {} base parameters; \
         largest relative error OLS {:.1e}, streamed {:.1e}, SDP {:.1e} ({}); pseudo-inertia \
         min eigenvalues {:?}",
        c.condition_number,
        c.random_condition_median,
        c.truth.len(),
        worst(&c.ols),
        worst(&c.streaming),
        worst(&c.sdp),
        c.sdp_status,
        c.min_eigenvalues
    );
    Ok(())
}
