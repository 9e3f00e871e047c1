//! scipy equivalence: Butterworth design, steady-state initial conditions and
//! zero-phase filtering against vectors written by
//! `tests/reference/make_reference.py` (scipy.signal.butter, sosfilt_zi,
//! sosfiltfilt, filtfilt).

use aras_signal::{Butterworth, FilterError, TransferFunction};
use serde_json::Value;

fn reference() -> Value {
    let text = include_str!("reference/butterworth.json");
    serde_json::from_str(text).expect("reference JSON parses")
}

fn vec_of(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// Largest absolute difference, scaled by the larger magnitude of 1 and the
/// reference value (relative for large values, absolute near zero).
fn max_err(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / y.abs().max(1.0))
        .fold(0.0, f64::max)
}

// The contract is 1e-10. The design is a handful of trigonometric and
// complex operations, and filtering recurses over a few hundred samples;
// both accumulate only rounding: the SOS results agree to 1e-13 (checked by
// lowering the tolerance), the 'ba' form to somewhat less because its
// polynomial coefficients amplify rounding. 1e-10 is tight yet leaves room
// for a different libm.
const TOL: f64 = 1e-10;

#[test]
fn butterworth_sections_match_scipy() {
    let r = reference();
    for case in r["sos"].as_array().unwrap() {
        let order = case["order"].as_u64().unwrap() as usize;
        let fc = case["cutoff_hz"].as_f64().unwrap();
        let fs = case["sample_rate_hz"].as_f64().unwrap();
        let sos = Butterworth::lowpass(order, fc, fs).unwrap();
        let expected: Vec<Vec<f64>> = case["sos"].as_array().unwrap().iter().map(vec_of).collect();
        assert_eq!(sos.sections().len(), expected.len(), "order {order}");
        for (got, want) in sos.sections().iter().zip(&expected) {
            assert!(
                max_err(got, want) < TOL,
                "order {order} fc {fc}: {got:?} vs {want:?}"
            );
        }
        let zi: Vec<Vec<f64>> = case["zi"].as_array().unwrap().iter().map(vec_of).collect();
        for (got, want) in sos.steady_state().iter().zip(&zi) {
            assert!(
                max_err(got, want) < TOL,
                "zi order {order}: {got:?} vs {want:?}"
            );
        }
        assert_eq!(
            sos.padlen() as u64,
            case["padlen"].as_u64().unwrap(),
            "padlen order {order}"
        );
    }
}

#[test]
fn sosfiltfilt_matches_scipy() {
    let r = reference();
    let mut checked = 0;
    for case in r["sos"].as_array().unwrap() {
        let order = case["order"].as_u64().unwrap() as usize;
        let fc = case["cutoff_hz"].as_f64().unwrap();
        let fs = case["sample_rate_hz"].as_f64().unwrap();
        let sos = Butterworth::lowpass(order, fc, fs).unwrap();
        for s in case["signals"].as_array().unwrap() {
            let x = vec_of(&s["x"]);
            let y = vec_of(&s["y"]);
            let got = sos.filtfilt(&x).unwrap();
            let e = max_err(&got, &y);
            assert!(
                e < TOL,
                "order {order} fc {fc} len {}: error {e:e}",
                x.len()
            );
            checked += 1;
        }
        // One sample shorter than the shortest accepted: scipy raises too.
        let padlen = sos.padlen();
        assert_eq!(
            sos.filtfilt(&vec![1.0; padlen]).unwrap_err(),
            FilterError::TooShort {
                len: padlen,
                padlen
            }
        );
    }
    assert_eq!(checked, 27);
}

#[test]
fn transfer_function_filtfilt_matches_scipy() {
    let r = reference();
    for case in r["ba"].as_array().unwrap() {
        let order = case["order"].as_u64().unwrap() as usize;
        let fc = case["cutoff_hz"].as_f64().unwrap();
        let fs = case["sample_rate_hz"].as_f64().unwrap();
        let b = vec_of(&case["b"]);
        let a = vec_of(&case["a"]);
        let ours = Butterworth::lowpass_ba(order, fc, fs).unwrap();
        assert!(max_err(ours.b(), &b) < TOL, "b order {order}");
        assert!(max_err(ours.a(), &a) < TOL, "a order {order}");
        let tf = TransferFunction::new(b, a).unwrap();
        assert_eq!(tf.padlen() as u64, case["padlen"].as_u64().unwrap());
        for s in case["signals"].as_array().unwrap() {
            let x = vec_of(&s["x"]);
            let y = vec_of(&s["y"]);
            let e = max_err(&tf.filtfilt(&x).unwrap(), &y);
            assert!(e < TOL, "ba order {order} len {}: error {e:e}", x.len());
        }
    }
}
