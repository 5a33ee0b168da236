//! Shared helpers of the model tests (included with `mod common;`).
#![allow(dead_code)]

use model::design::{generate_model, DesignLengths};
use model::PlanarModel;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The hardware ADAM from GenerateModel.
pub fn adam() -> PlanarModel {
    generate_model(&DesignLengths::ADAM)
        .expect("ADAM generates")
        .0
}

/// A seeded generator.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// A random configuration: base anywhere near standing, every joint inside its limits.
pub fn random_q(model: &PlanarModel, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut q = vec![0.0; model.dof()];
    q[0] = rng.random_range(-1.0..1.0);
    q[1] = rng.random_range(0.3..0.8);
    q[2] = rng.random_range(-0.6..0.6);
    for j in &model.joints {
        let (lo, hi) = (j.lower.max(-2.0), j.upper.min(2.0));
        q[j.coordinate] = rng.random_range(lo..hi);
    }
    q
}

/// A random velocity, ±`scale` on every coordinate.
pub fn random_dq(model: &PlanarModel, rng: &mut ChaCha8Rng, scale: f64) -> Vec<f64> {
    (0..model.dof())
        .map(|_| rng.random_range(-scale..scale))
        .collect()
}

/// Largest absolute entry difference, relative to the larger of the two largest entries.
pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().chain(b).fold(1e-12_f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}
