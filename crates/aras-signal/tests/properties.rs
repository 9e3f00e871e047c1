//! Invariants of the zero-phase filter (proptest).

use aras_signal::Butterworth;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Filtering many signals together, interleaved in SIMD lanes, gives
    /// exactly (bit for bit) what filtering each alone gives: any count of
    /// signals (fewer than, equal to and more than the lane count), any
    /// order (odd orders have a lone first-order section), any length.
    #[test]
    fn many_signals_at_once_are_bit_identical_to_one_at_a_time(
        order in 1usize..=8,
        frac in 0.005f64..0.45,
        count in 1usize..20,
        extra in 1usize..300,
        seed in any::<u64>(),
    ) {
        let fs = 1000.0;
        let sos = Butterworth::lowpass(order, frac * fs, fs).unwrap();
        let n = sos.padlen() + extra;
        let mut state = seed | 1;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let signals: Vec<Vec<f64>> =
            (0..count).map(|_| (0..n).map(|_| next()).collect()).collect();
        let mut together = signals.clone();
        let mut views: Vec<&mut [f64]> = together.iter_mut().map(|s| s.as_mut_slice()).collect();
        sos.filtfilt_many_in_place(&mut views, &mut Vec::new()).unwrap();
        for (s, t) in signals.iter().zip(&together) {
            let alone = sos.filtfilt(s).unwrap();
            prop_assert!(alone.iter().zip(t).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }

    /// A constant passes unchanged: unit DC gain and steady-state initial
    /// conditions leave no start-up transient. Rounding only: 1e-12 relative,
    /// growing as 1/f for very low cut-offs, whose poles sit within ~2π·f/fs
    /// of the unit circle and amplify rounding accordingly (observed: 2.3e-12
    /// at order 6 and f = 0.001·fs).
    #[test]
    fn constant_in_constant_out(
        order in 1usize..=8,
        frac in 0.001f64..0.45,
        c in -1e3f64..1e3,
        extra in 1usize..200,
    ) {
        let fs = 1000.0;
        let sos = Butterworth::lowpass(order, frac * fs, fs).unwrap();
        let x = vec![c; sos.padlen() + extra];
        let tol = 1e-12 * c.abs().max(1.0) * (1.0 + 0.01 / frac);
        for y in sos.filtfilt(&x).unwrap() {
            prop_assert!((y - c).abs() <= tol, "{y} vs {c}");
        }
        for y in sos.filtfilt_periodic(&x).unwrap() {
            prop_assert!((y - c).abs() <= tol, "{y} vs {c}");
        }
    }

    /// A sinusoid below the cut-off comes out scaled by |H(f)|² with no phase
    /// lag: y = |H|²·x sample by sample, away from the record's ends.
    #[test]
    fn no_phase_lag_below_cutoff(
        order in 1usize..=6,
        cutoff in 20.0f64..100.0,
        ratio in 0.05f64..0.8,
        phase in 0.0f64..std::f64::consts::TAU,
    ) {
        let fs = 1000.0;
        let f = ratio * cutoff;
        let sos = Butterworth::lowpass(order, cutoff, fs).unwrap();
        let g2 = sos.gain(f, fs).powi(2);
        let n = 4000;
        let x: Vec<f64> = (0..n)
            .map(|i| (std::f64::consts::TAU * f * i as f64 / fs + phase).sin())
            .collect();
        let y = sos.filtfilt(&x).unwrap();
        // The start-up transient of the slowest pole (≤ 31 samples per time
        // constant at fc ≥ 20 Hz, order ≤ 6) is below 1e-9 after 1000 samples.
        // A lag of one sample would show as an error ≈ 2π f/fs ≥ 6e-3.
        for i in 1000..n - 1000 {
            prop_assert!((y[i] - g2 * x[i]).abs() < 1e-8, "i {i}: {} vs {}", y[i], g2 * x[i]);
        }
    }
}

/// `filtfilt_record` is the periodic filter for periodic records and the
/// padded one otherwise, bit for bit.
#[test]
fn filtfilt_record_chooses_by_the_kind_of_record() {
    let sos = Butterworth::lowpass(4, 10.0, 1000.0).unwrap();
    let x: Vec<f64> = (0..500)
        .map(|i| (i as f64 * 0.05).sin() + 0.1 * (i % 7) as f64)
        .collect();
    assert_eq!(
        sos.filtfilt_record(&x, true).unwrap(),
        sos.filtfilt_periodic(&x).unwrap()
    );
    assert_eq!(
        sos.filtfilt_record(&x, false).unwrap(),
        sos.filtfilt(&x).unwrap()
    );
}
