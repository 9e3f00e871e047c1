//! Fast, exact decimal-to-f64 parsing for log fields.
//!
//! Most logged numbers have at most 15–16 significant digits and a small
//! decimal exponent. For those, `mantissa · 10^e` with `mantissa ≤ 2^53` and
//! `|e| ≤ 22` is one correctly rounded IEEE multiplication or division of two
//! exactly representable numbers (Clinger's fast path), so the result equals
//! `str::parse::<f64>`. Everything else (long mantissas, large exponents,
//! `inf`, `nan`, junk) goes to the standard library parser.

const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parses a trimmed field; `None` if it is not a number.
///
/// Fields longer than 17 bytes cannot take the fast path (more than 15–16
/// digits), so they go straight to the standard parser instead of being
/// scanned twice.
#[inline]
pub(crate) fn parse_f64(s: &[u8]) -> Option<f64> {
    if s.len() <= 17
        && let Some(v) = fast(s)
    {
        return Some(v);
    }
    std::str::from_utf8(s).ok()?.parse().ok()
}

#[inline]
fn fast(s: &[u8]) -> Option<f64> {
    let mut i = 0;
    let neg = match s.first()? {
        b'-' => {
            i = 1;
            true
        }
        b'+' => {
            i = 1;
            false
        }
        _ => false,
    };
    let mut mantissa: u64 = 0;
    let mut digits = 0u32;
    let mut exp: i64 = 0;
    while i < s.len() && s[i].is_ascii_digit() {
        mantissa = mantissa
            .wrapping_mul(10)
            .wrapping_add(u64::from(s[i] - b'0'));
        digits += 1;
        i += 1;
    }
    if i < s.len() && s[i] == b'.' {
        i += 1;
        while i < s.len() && s[i].is_ascii_digit() {
            mantissa = mantissa
                .wrapping_mul(10)
                .wrapping_add(u64::from(s[i] - b'0'));
            digits += 1;
            exp -= 1;
            i += 1;
        }
    }
    if digits == 0 || digits > 19 {
        return None;
    }
    if i < s.len() && (s[i] == b'e' || s[i] == b'E') {
        i += 1;
        let eneg = match s.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let start = i;
        let mut e: i64 = 0;
        while i < s.len() && s[i].is_ascii_digit() && i - start < 5 {
            e = e * 10 + i64::from(s[i] - b'0');
            i += 1;
        }
        if i == start {
            return None;
        }
        exp += if eneg { -e } else { e };
    }
    if i != s.len() || mantissa > (1u64 << 53) || !(-22..=22).contains(&exp) {
        return None;
    }
    let m = mantissa as f64;
    let v = if exp >= 0 {
        m * POW10[exp as usize]
    } else {
        m / POW10[(-exp) as usize]
    };
    Some(if neg { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn parses_like_std() {
        for s in [
            "0",
            "-0",
            "1",
            "+1.5",
            "0.001",
            "123.456e-3",
            "1E5",
            ".5",
            "5.",
            "-7.25e+2",
            "0.1234567890123456",
            "3.141592653589793",
            "12345678901234567890",
            "1e300",
            "4.9e-324",
            "inf",
            "-inf",
            "NaN",
        ] {
            let ours = parse_f64(s.as_bytes()).unwrap();
            let std: f64 = s.parse().unwrap();
            assert!(
                ours == std || (ours.is_nan() && std.is_nan()),
                "{s}: {ours} vs {std}"
            );
        }
        for s in ["", "-", "1.2.3", "abc", "1e", "1,5", "0x10", "1 2", ";"] {
            assert_eq!(parse_f64(s.as_bytes()), None, "{s}");
        }
    }

    proptest! {
        /// Every f64 printed shortest-round-trip or with fixed decimals parses
        /// back bit-exactly, whichever path takes it.
        #[test]
        fn round_trips(v in proptest::num::f64::NORMAL | proptest::num::f64::ZERO, d in 0usize..12) {
            let s = format!("{v}");
            prop_assert_eq!(parse_f64(s.as_bytes()).unwrap().to_bits(), s.parse::<f64>().unwrap().to_bits());
            let s = format!("{v:.d$}");
            prop_assert_eq!(parse_f64(s.as_bytes()).unwrap().to_bits(), s.parse::<f64>().unwrap().to_bits());
            let s = format!("{v:e}");
            prop_assert_eq!(parse_f64(s.as_bytes()).unwrap().to_bits(), s.parse::<f64>().unwrap().to_bits());
        }
    }
}
