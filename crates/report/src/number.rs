//! Numbers as the report prints them.

/// A number with 4 significant digits: integers as they are, scientific notation for the
/// very large and very small, `not finite` for NaN and infinities.
pub fn short(x: f64) -> String {
    if !x.is_finite() {
        return "not finite".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    if x.fract() == 0.0 && x.abs() < 1e9 {
        return format!("{x:.0}");
    }
    if (1e-3..1e5).contains(&x.abs()) {
        let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
        return format!("{x:.digits$}");
    }
    format!("{x:.3e}")
}

/// A value of the scenario file as written there (shortest form), or in scientific
/// notation when long.
pub fn setting(x: f64) -> String {
    let plain = format!("{x}");
    if plain.len() <= 10 {
        plain
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prints_numbers_briefly() {
        assert_eq!(short(0.0017234), "0.001723");
        assert_eq!(short(512.0), "512");
        assert_eq!(short(1e308), "1.000e308");
        assert_eq!(short(f64::NAN), "not finite");
        assert_eq!(setting(0.49), "0.49");
        assert_eq!(setting(-5.0), "-5");
        assert_eq!(setting(1e308), "1e308");
        assert_eq!(setting(f64::INFINITY), "inf");
    }
}
