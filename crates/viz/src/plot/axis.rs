//! Axis ranges and tick labels. Ranges are worked out in "axis space": the value itself on a linear
//! axis, log10 of it on a logarithmic one, where clipping and padding are linear.

use crate::error::VizError;

/// One axis: whether it is logarithmic, and its range in axis space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Axis {
    pub log: bool,
    pub lo: f64,
    pub hi: f64,
}

/// Fraction of the data span added on each side of an automatic linear range.
const PAD: f64 = 0.04;

impl Axis {
    /// The axis-space coordinate of `v`: NaN where the value cannot be shown (non-finite, or ≤ 0 on a
    /// log axis).
    #[inline]
    pub fn axis_coord(log: bool, v: f64) -> f64 {
        match (log, v.is_finite()) {
            (_, false) => f64::NAN,
            (false, true) => v,
            (true, true) if v > 0.0 => v.log10(),
            (true, true) => f64::NAN,
        }
    }

    #[inline]
    pub fn data_coord(&self, u: f64) -> f64 {
        if self.log { 10f64.powf(u) } else { u }
    }

    /// The range in data units.
    pub fn data_range(&self) -> (f64, f64) {
        (self.data_coord(self.lo), self.data_coord(self.hi))
    }

    /// An axis over `given` when set (checked), else over the finite values of `data` (already in axis
    /// space): padded by a few per cent on a linear axis, widened to whole decades on a log one.
    pub fn resolve(
        name: &'static str,
        log: bool,
        given: Option<(f64, f64)>,
        data: impl Iterator<Item = f64>,
    ) -> Result<Self, VizError> {
        if let Some((min, max)) = given {
            let invalid = |reason| VizError::InvalidRange { axis: name, min, max, reason };
            if !(min.is_finite() && max.is_finite()) {
                return Err(invalid("both ends must be finite"));
            }
            if min >= max {
                return Err(invalid("the minimum must be below the maximum"));
            }
            if log && min <= 0.0 {
                return Err(invalid("a logarithmic axis needs a positive minimum"));
            }
            return Ok(Self { log, lo: Self::axis_coord(log, min), hi: Self::axis_coord(log, max) });
        }
        let (lo, hi) = data
            .filter(|u| u.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), u| (lo.min(u), hi.max(u)));
        let (lo, hi) = if lo > hi {
            (0.0, 1.0)
        } else if log {
            let (lo, hi) = (lo.floor(), hi.ceil());
            if lo == hi { (lo - 1.0, hi + 1.0) } else { (lo, hi) }
        } else if hi - lo <= 1e-12 * lo.abs().max(hi.abs()) {
            let half = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
            (lo - half, hi + half)
        } else {
            let pad = PAD * (hi - lo);
            (lo - pad, hi + pad)
        };
        Ok(Self { log, lo, hi })
    }

    /// Whether axis-space `u` lies on the axis (with a hair of tolerance for rounding).
    #[inline]
    pub fn contains(&self, u: f64) -> bool {
        let tol = 1e-9 * (self.hi - self.lo);
        u >= self.lo - tol && u <= self.hi + tol
    }

    /// Where axis-space `u` lies along the axis, 0 at `lo` and 1 at `hi`.
    #[inline]
    pub fn fraction(&self, u: f64) -> f64 {
        (u - self.lo) / (self.hi - self.lo)
    }
}

impl Axis {
    /// Labelled ("bold") and unlabelled ("light") tick values of a log axis, in data units: every
    /// decade, or every second, fifth, … decade when there are many; with 2–9 × 10ⁿ as light ticks (or
    /// as labels too when the axis spans less than a decade or two). plotters' own log ticks stop at
    /// 2.2·10⁻¹⁶, which error plots go below.
    pub fn log_ticks(&self) -> (Vec<f64>, Vec<f64>) {
        const MAX_LABELS: i64 = 10;
        let (first, last) = (self.lo.ceil() as i64, self.hi.floor() as i64);
        let n_decades = (last - first + 1).max(0);
        let stride =
            [1, 2, 3, 5, 10, 20, 50, 100].into_iter().find(|&k| n_decades / k < MAX_LABELS).unwrap_or(200);
        let in_range = |v: f64| self.contains(v.log10());
        let decade = |k: i64| format!("1e{k}").parse::<f64>().unwrap_or(f64::NAN);
        let minor = |k: i64| (1..10).map(move |m| format!("{m}e{k}").parse::<f64>().unwrap_or(f64::NAN));
        let all_minor: Vec<f64> =
            (self.lo.floor() as i64..=last).flat_map(minor).filter(|&v| in_range(v)).collect();
        if n_decades < 2 {
            let bold = all_minor
                .iter()
                .copied()
                .filter(|v| {
                    let m = (v / decade(v.log10().floor() as i64)).round();
                    m == 1.0 || m == 2.0 || m == 5.0
                })
                .collect();
            return (bold, all_minor);
        }
        let bold: Vec<f64> = (first..=last).filter(|k| k.rem_euclid(stride) == 0).map(decade).collect();
        let light =
            if stride == 1 && n_decades <= 8 { all_minor } else { (first..=last).map(decade).collect() };
        (bold, light)
    }

    /// Roughly the tick labels plotters will draw on a linear axis (a 1–2–5 step giving about eight
    /// ticks), or the log ticks; used to size the space beside the axis.
    pub fn approximate_tick_labels(&self) -> Vec<String> {
        let values = if self.log {
            self.log_ticks().0
        } else {
            let raw = (self.hi - self.lo) / 8.0;
            let magnitude = 10f64.powf(raw.log10().floor());
            let step =
                [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * magnitude).find(|&s| s >= raw).unwrap_or(raw);
            let first = (self.lo / step).ceil() as i64;
            let last = (self.hi / step).floor() as i64;
            (first..=last.min(first + 50)).map(|k| k as f64 * step).collect()
        };
        values.into_iter().map(|v| tick_label(v, self.log)).collect()
    }
}

/// A tick label: short decimals, scientific notation for very large or small magnitudes, and powers of
/// ten as 10ⁿ on a log axis.
pub(crate) fn tick_label(v: f64, log: bool) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".to_owned() } else { format!("{v}") };
    }
    let exponent = v.abs().log10();
    if log && (exponent - exponent.round()).abs() < 1e-9 {
        return format!("10{}", superscript(exponent.round() as i32));
    }
    if !(1e-3..1e5).contains(&v.abs()) {
        let s = format!("{v:.2e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        return format!("{}e{exp}", trim_zeros(mantissa));
    }
    // Six significant digits are enough to tell ticks apart and hide binary rounding (0.30000000000000004).
    let decimals = (5 - exponent.floor() as i32).clamp(0, 9) as usize;
    trim_zeros(&format!("{v:.decimals$}")).to_owned()
}

fn trim_zeros(s: &str) -> &str {
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { s }
}

fn superscript(n: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if n < 0 {
        s.push('⁻');
    }
    for c in n.unsigned_abs().to_string().bytes() {
        s.push(DIGITS[usize::from(c - b'0')]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(0.30000000000000004, false), "0.3");
        assert_eq!(tick_label(-2.5, false), "-2.5");
        assert_eq!(tick_label(0.0, false), "0");
        assert_eq!(tick_label(1500.0, false), "1500");
        assert_eq!(tick_label(2.5e-6, false), "2.5e-6");
        assert_eq!(tick_label(1e-6, true), "10⁻⁶");
        assert_eq!(tick_label(100.0, true), "10²");
        assert_eq!(tick_label(200.0, true), "200");
        assert_eq!(tick_label(1e4, true), "10⁴");
    }

    #[test]
    fn log_ticks_reach_far_below_machine_epsilon() {
        let axis = Axis { log: true, lo: -19.0, hi: 0.0 };
        let (bold, light) = axis.log_ticks();
        assert!(bold.len() <= 10 && bold.len() >= 5, "{bold:?}");
        assert!(bold.iter().any(|&v| v < 1e-16), "{bold:?}");
        assert!(light.len() >= bold.len());
        let narrow = Axis { log: true, lo: 0.2, hi: 0.9 };
        let (bold, _) = narrow.log_ticks();
        assert_eq!(bold, vec![2.0, 5.0]);
    }

    #[test]
    fn ranges_are_padded_checked_and_survive_no_data() {
        let a = Axis::resolve("x", false, None, [0.0, 10.0].into_iter()).unwrap();
        assert!(a.lo < 0.0 && a.hi > 10.0 && a.hi < 11.0);
        let l = Axis::resolve("y", true, None, [-3.2, 0.4].into_iter()).unwrap();
        assert_eq!((l.lo, l.hi), (-4.0, 1.0));
        let none = Axis::resolve("x", false, None, [f64::NAN].into_iter()).unwrap();
        assert_eq!((none.lo, none.hi), (0.0, 1.0));
        let flat = Axis::resolve("x", false, None, [2.0, 2.0].into_iter()).unwrap();
        assert!(flat.lo < 2.0 && flat.hi > 2.0);
        assert!(Axis::resolve("y", true, Some((0.0, 1.0)), std::iter::empty()).is_err());
        assert!(Axis::resolve("y", false, Some((1.0, 1.0)), std::iter::empty()).is_err());
        assert!(Axis::resolve("y", false, Some((f64::NAN, 1.0)), std::iter::empty()).is_err());
    }
}
