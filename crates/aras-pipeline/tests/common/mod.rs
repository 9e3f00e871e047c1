//! Shared helpers of the pipeline's integration tests.
#![allow(dead_code)]

use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};

pub fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

pub fn normal(r: &mut StdRng) -> f64 {
    StandardNormal.sample(r)
}

/// Task-space mass matrix (33) of `params` checked for positive
/// definiteness over the paper's workspace box (77): `grid` × `grid`
/// points plus `random` ones.
pub fn task_mass_pd(
    params: &aras_dyn::Params,
    grid: usize,
    random: usize,
) -> aras_ident::validate::PdReport<2> {
    use aras_ident::validate::{PdRegion, check_positive_definite};
    use nalgebra::Vector2;
    let dy = aras_dyn::Dynamics::new(params).unwrap();
    let ws = aras_kin::Workspace::paper();
    let mut region = PdRegion::new([ws.min()[0], ws.min()[1]], [ws.max()[0], ws.max()[1]]);
    region.grid_per_axis = grid;
    region.random = random;
    let z = Vector2::zeros();
    check_positive_definite(
        |x: &[f64; 2]| -> Result<[[f64; 2]; 2], String> {
            let s = dy
                .sample(&aras_kin::Motion::new(Vector2::new(x[0], x[1]), z, z))
                .map_err(|e| e.to_string())?;
            let m = dy.mass_matrix(&s);
            Ok([[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]])
        },
        &region,
    )
}
