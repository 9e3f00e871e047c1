//! Runs the per-sample evaluation in a loop (for profilers: `valgrind
//! --tool=callgrind` counts instructions, repeatable on a busy machine).

use aras_kin::{Geometry, evaluate};
use nalgebra::Vector2;
use std::hint::black_box;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1_000_000);
    let g = Geometry::aras_diamond();
    let mut acc = 0.0;
    for i in 0..n {
        let t = i as f64 * 1e-3;
        let x = Vector2::new(1.5 + 0.5 * t.sin(), 1.0 + 0.3 * t.cos());
        let s = evaluate(
            &g,
            &aras_kin::Motion::new(
                *black_box(&x),
                Vector2::new(0.3, -0.7),
                Vector2::new(1.1, 0.4),
            ),
        )
        .unwrap();
        acc += s.omega_dot[3][2];
    }
    println!("{acc}");
}
