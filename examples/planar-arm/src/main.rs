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
    Ok(())
}
