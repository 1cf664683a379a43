//! Number formatting shared by tables, figures and the README: fixed rules, so the same value
//! always prints the same text.

/// `v` with `digits` significant digits, trailing zeros trimmed (`0.0123`, `17.8`, `101720`);
/// empty for NaN and infinities.
pub fn sig(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return String::new();
    }
    if v == 0.0 {
        return "0".into();
    }
    let magnitude = v.abs().log10().floor() as i64;
    let decimals = (digits as i64 - 1 - magnitude).max(0) as usize;
    // Rounding can carry into a new digit (9.9996 -> 10.000); that only adds a trailing zero.
    let text = format!("{v:.decimals$}");
    trim_zeros(&text)
}

/// Removes trailing zeros after a decimal point (and the point itself), and a minus before 0.
fn trim_zeros(text: &str) -> String {
    let trimmed = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        text
    };
    if trimmed == "-0" {
        "0".into()
    } else {
        trimmed.to_string()
    }
}

/// `v` with a fixed number of decimals, trailing zeros kept (`0.50`), empty for non-finite (the
/// questionnaire tables' rule, [`rmt_analysis::tables::number`]).
pub fn fixed(v: f64, decimals: usize) -> String {
    rmt_analysis::tables::number(v, decimals)
}

/// A count with thousands separators (`101,720`); empty for non-finite.
pub fn count(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let rounded = v.round();
    let digits = format!("{}", rounded.abs() as u64);
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    if rounded < 0.0 {
        format!("-{out}")
    } else {
        out
    }
}

/// A share as a percentage with one decimal (`39.4%`).
pub fn percent(share: f64) -> String {
    if share.is_finite() {
        format!("{}%", fixed(share * 100.0, 1))
    } else {
        String::new()
    }
}

/// A readable display of a value in `unit`: 3 significant digits, at least the integer part.
pub fn readable(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    if v.abs() >= 100.0 {
        fixed(v, 0)
    } else {
        sig(v, 3)
    }
}

/// The time unit that makes `max_seconds` read as a number between about 1 and 1000:
/// (multiplier from seconds, unit name).
pub fn time_unit(max_seconds: f64) -> (f64, &'static str) {
    if max_seconds >= 1.0 {
        (1.0, "s")
    } else if max_seconds >= 1e-3 {
        (1e3, "ms")
    } else {
        (1e6, "µs")
    }
}

/// The time unit for values that span orders of magnitude: the one that suits their median.
pub fn time_unit_median(seconds: &[f64]) -> (f64, &'static str) {
    let mut v: Vec<f64> = seconds.iter().copied().filter(|t| t.is_finite()).collect();
    if v.is_empty() {
        return time_unit(0.0);
    }
    v.sort_by(f64::total_cmp);
    time_unit(v[v.len() / 2])
}

/// A byte count in KiB or MiB with 3 significant digits (`1.06 MiB`).
pub fn bytes(v: f64) -> String {
    if !v.is_finite() {
        String::new()
    } else if v >= 1024.0 * 1024.0 {
        format!("{} MiB", sig(v / (1024.0 * 1024.0), 3))
    } else if v >= 1024.0 {
        format!("{} KiB", sig(v / 1024.0, 3))
    } else {
        format!("{} B", fixed(v, 0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits_are_kept_and_zeros_trimmed() {
        assert_eq!(sig(0.0123456, 3), "0.0123");
        assert_eq!(sig(17.8449, 3), "17.8");
        assert_eq!(sig(101720.0, 6), "101720");
        assert_eq!(sig(101720.4, 3), "101720");
        assert_eq!(sig(2.0, 6), "2");
        assert_eq!(sig(-0.0000001, 2), "-0.0000001");
        assert_eq!(sig(9.9996, 3), "10");
        assert_eq!(sig(f64::NAN, 3), "");
    }

    #[test]
    fn counts_get_thousands_separators() {
        assert_eq!(count(101720.0), "101,720");
        assert_eq!(count(999.0), "999");
        assert_eq!(count(1000.0), "1,000");
        assert_eq!(count(1234567.0), "1,234,567");
        assert_eq!(count(-1234.0), "-1,234");
    }

    #[test]
    fn fixed_and_percent_drop_negative_zero() {
        assert_eq!(fixed(-0.0001, 2), "0.00");
        assert_eq!(percent(0.39412), "39.4%");
        assert_eq!(readable(1234.56), "1235");
        assert_eq!(readable(0.01234), "0.0123");
    }

    #[test]
    fn time_units_follow_the_magnitude() {
        assert_eq!(time_unit(2.5), (1.0, "s"));
        assert_eq!(time_unit(0.0178), (1e3, "ms"));
        assert_eq!(time_unit(0.0000178), (1e6, "µs"));
        assert_eq!(time_unit_median(&[0.002, 0.1, 3.2]), (1e3, "ms"));
        assert_eq!(bytes(1220760.0), "1.16 MiB");
        assert_eq!(bytes(2048.0), "2 KiB");
    }
}
