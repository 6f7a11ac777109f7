//! Turning a series into what can be drawn: polylines clipped to the plot rectangle, broken wherever a
//! point cannot be shown (NaN, infinite, or ≤ 0 on a log axis), and the markers inside the rectangle.

use super::LegendPosition;
use super::axis::Axis;

/// The drawable parts of one series, in data units.
#[derive(Debug, Default)]
pub(crate) struct Clipped {
    pub polylines: Vec<Vec<(f64, f64)>>,
    pub markers: Vec<(f64, f64)>,
}

/// Clips `points` to the rectangle of `x` × `y`. Clipping happens in axis space, where lines are straight.
pub(crate) fn clip_series(points: &[(f64, f64)], x: &Axis, y: &Axis) -> Clipped {
    let in_axis_space = |&(px, py): &(f64, f64)| (Axis::axis_coord(x.log, px), Axis::axis_coord(y.log, py));
    let to_data = |(u, v): (f64, f64)| (x.data_coord(u), y.data_coord(v));
    let shown = |(u, v): (f64, f64)| u.is_finite() && v.is_finite();

    let mut out = Clipped::default();
    let mut current: Vec<(f64, f64)> = Vec::new();
    // Whether `current` ends exactly at the previous point, so the next segment continues it.
    let mut open = false;
    for (i, p) in points.iter().map(in_axis_space).enumerate() {
        if shown(p) && x.contains(p.0) && y.contains(p.1) {
            out.markers.push(to_data(p));
        }
        let Some(q) = i.checked_sub(1).map(|k| in_axis_space(&points[k])) else { continue };
        // q is the previous point, p the current one: the segment runs q → p.
        let clipped = if shown(q) && shown(p) { clip_segment(q, p, x, y) } else { None };
        match clipped {
            Some((t0, t1)) => {
                if !(open && t0 == 0.0) {
                    finish(&mut current, &mut out);
                    current.push(to_data(lerp(q, p, t0)));
                }
                current.push(to_data(lerp(q, p, t1)));
                open = t1 == 1.0;
            }
            None => {
                finish(&mut current, &mut out);
                open = false;
            }
        }
    }
    finish(&mut current, &mut out);
    out
}

fn finish(current: &mut Vec<(f64, f64)>, out: &mut Clipped) {
    if current.len() >= 2 {
        out.polylines.push(std::mem::take(current));
    }
    current.clear();
}

/// The part of segment p → q inside the rectangle as parameters 0 ≤ t0 < t1 ≤ 1 (Liang–Barsky), or
/// `None` when it misses the rectangle or its direction overflows.
fn clip_segment(p: (f64, f64), q: (f64, f64), x: &Axis, y: &Axis) -> Option<(f64, f64)> {
    let d = (q.0 - p.0, q.1 - p.1);
    if !(d.0.is_finite() && d.1.is_finite()) {
        return None;
    }
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (delta, dist) in [(-d.0, p.0 - x.lo), (d.0, x.hi - p.0), (-d.1, p.1 - y.lo), (d.1, y.hi - p.1)] {
        if delta == 0.0 {
            if dist < 0.0 {
                return None;
            }
        } else {
            let t = dist / delta;
            if delta < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 < t1).then_some((t0, t1))
}

/// p + t (q − p), returning the end points themselves at t = 0 and t = 1 so polylines join exactly.
fn lerp(p: (f64, f64), q: (f64, f64), t: f64) -> (f64, f64) {
    if t == 0.0 {
        p
    } else if t == 1.0 {
        q
    } else {
        (p.0 + (q.0 - p.0) * t, p.1 + (q.1 - p.1) * t)
    }
}

/// The corner whose box of `box_w × box_h` (fractions of the plot area) covers the fewest samples of
/// the drawn data, preferring upper right, upper left, lower right, lower left on ties.
pub(crate) fn quietest_corner(
    series: &[Clipped],
    x: &Axis,
    y: &Axis,
    box_w: f64,
    box_h: f64,
) -> LegendPosition {
    const SAMPLES_PER_SEGMENT: usize = 8;
    let corners = [
        (LegendPosition::UpperRight, 1.0 - box_w, 1.0 - box_h),
        (LegendPosition::UpperLeft, 0.0, 1.0 - box_h),
        (LegendPosition::LowerRight, 1.0 - box_w, 0.0),
        (LegendPosition::LowerLeft, 0.0, 0.0),
    ];
    let mut counts = [0usize; 4];
    let mut count = |(px, py): (f64, f64)| {
        let (fx, fy) = (x.fraction(Axis::axis_coord(x.log, px)), y.fraction(Axis::axis_coord(y.log, py)));
        for (n, &(_, cx, cy)) in counts.iter_mut().zip(&corners) {
            if fx >= cx && fx <= cx + box_w && fy >= cy && fy <= cy + box_h {
                *n += 1;
            }
        }
    };
    for s in series {
        s.markers.iter().copied().for_each(&mut count);
        for line in &s.polylines {
            for w in line.windows(2) {
                // Sample in axis space so a long log-axis segment is sampled evenly along what is drawn.
                let (p, q) = (axis_point(w[0], x, y), axis_point(w[1], x, y));
                for k in 0..SAMPLES_PER_SEGMENT {
                    let (u, v) = lerp(p, q, k as f64 / SAMPLES_PER_SEGMENT as f64);
                    count((x.data_coord(u), y.data_coord(v)));
                }
            }
        }
    }
    let best = (0..4).min_by_key(|&k| counts[k]).unwrap_or(0);
    corners[best].0
}

fn axis_point((px, py): (f64, f64), x: &Axis, y: &Axis) -> (f64, f64) {
    (Axis::axis_coord(x.log, px), Axis::axis_coord(y.log, py))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Axis {
        Axis { log: false, lo: 0.0, hi: 1.0 }
    }

    #[test]
    fn nan_breaks_a_line_and_outside_parts_are_cut() {
        let pts = [
            (0.1, 0.1),
            (0.2, 0.2),
            (f64::NAN, 0.5),
            (0.5, 0.5),
            (0.6, 0.6),
            (0.7, 5.0),
            (0.8, 0.5),
            (0.9, 0.5),
        ];
        let c = clip_series(&pts, &unit(), &unit());
        assert_eq!(c.polylines.len(), 3, "{:?}", c.polylines);
        let rising = &c.polylines[1];
        assert_eq!(rising.first(), Some(&(0.5, 0.5)));
        let top = rising.last().unwrap();
        assert!((top.1 - 1.0).abs() < 1e-12, "clipped at y = {}", top.1);
        assert!(c.polylines.iter().flatten().all(|p| p.0.is_finite() && p.1 <= 1.0 + 1e-12));
        assert_eq!(c.markers.len(), 6);
    }

    #[test]
    fn diverging_series_is_clipped_not_dropped() {
        let pts: Vec<(f64, f64)> = (0..400).map(|k| (k as f64 * 0.01, (k as f64 * 0.5).exp())).collect();
        let y = Axis { log: false, lo: 0.0, hi: 10.0 };
        let x = Axis { log: false, lo: 0.0, hi: 4.0 };
        let c = clip_series(&pts, &x, &y);
        assert_eq!(c.polylines.len(), 1);
        assert!(c.polylines[0].iter().all(|p| p.1 <= 10.0 + 1e-9));
    }

    #[test]
    fn log_axis_drops_non_positive_points() {
        let x = Axis { log: true, lo: -2.0, hi: 2.0 };
        let pts = [(0.01, 0.5), (0.1, 0.5), (0.0, 0.5), (1.0, 0.5), (10.0, 0.5)];
        let c = clip_series(&pts, &x, &unit());
        assert_eq!(c.polylines.len(), 2);
        assert!((c.polylines[1][1].0 - 10.0).abs() < 1e-12);
    }
}
