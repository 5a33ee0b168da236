//! Seeded Gaussian noise: the one standard-normal sampler of the simulated sensors (the A1
//! encoders in [`crate::sim::firmware`], the IMU in [`crate::imu`]).
//!
//! The Ziggurat method of `rand_distr` (one 64-bit draw and a table lookup for 99 % of the
//! samples): the encoders draw one sample per motor per 10 kHz firmware tick, where Box–Muller
//! (two uniform draws, a logarithm, a square root and a cosine per sample) took about a sixth of
//! the simulator's time. Deterministic: the same generator state gives the same samples.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Standard normal sample, from the seeded generator only.
pub(crate) fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    rng.sample(StandardNormal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn moments_and_tails_are_those_of_a_standard_normal() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let n = 400_000;
        let (mut sum, mut sum2, mut sum4, mut beyond_2, mut beyond_3) = (0.0, 0.0, 0.0, 0, 0);
        for _ in 0..n {
            let x = gaussian(&mut rng);
            sum += x;
            sum2 += x * x;
            sum4 += x * x * x * x;
            beyond_2 += usize::from(x.abs() > 2.0);
            beyond_3 += usize::from(x.abs() > 3.0);
        }
        let n_f = f64::from(n);
        let mean = sum / n_f;
        let variance = sum2 / n_f - mean * mean;
        let kurtosis = sum4 / n_f / (variance * variance);
        // Standard errors at n = 4e5: mean 0.0016, variance 0.0022, kurtosis 0.008.
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((variance - 1.0).abs() < 0.01, "variance {variance}");
        assert!((kurtosis - 3.0).abs() < 0.05, "kurtosis {kurtosis}");
        // P(|x| > 2) = 0.0455, P(|x| > 3) = 0.0027 (the Ziggurat's tail and wedge paths).
        let p2 = beyond_2 as f64 / n_f;
        let p3 = beyond_3 as f64 / n_f;
        assert!((p2 - 0.0455).abs() < 0.002, "P(|x| > 2) = {p2}");
        assert!((p3 - 0.0027).abs() < 0.0005, "P(|x| > 3) = {p3}");
    }

    #[test]
    fn the_same_seed_gives_the_same_samples() {
        let mut a = ChaCha8Rng::seed_from_u64(5);
        let mut b = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..1000 {
            assert_eq!(gaussian(&mut a).to_bits(), gaussian(&mut b).to_bits());
        }
    }
}
