//! The exact line search of the contact Newton: the minimizer, along one step, of its
//! convex piecewise quadratic objective.

use super::cone::edges;
use crate::contact::local_row::LocalRow;

/// The line of one Newton step: the objective's derivative and slope along it.
pub(super) struct Line<'a> {
    pub(super) rows: &'a [LocalRow],
    pub(super) stiffness: &'a [f64],
    pub(super) value: &'a [[f64; 2]],
    pub(super) slope: &'a [[f64; 2]],
    /// `Σ Pa·W Pb` and `Σ Pb·W Pb` of the masses' term.
    pub(super) mass: (f64, f64),
}

impl Line<'_> {
    /// `f'(α)` and `f''(α⁺)`.
    fn derivative(&self, alpha: f64) -> (f64, f64) {
        let (mut d, mut dd) = (self.mass.0 + alpha * self.mass.1, self.mass.1);
        for (r, row) in self.rows.iter().enumerate() {
            let k = self.stiffness[r];
            if k == 0.0 {
                continue;
            }
            for e in 0..edges(row.friction) {
                let v = self.slope[r][e];
                let u = self.value[r][e] + alpha * v;
                if u < 0.0 || (u == 0.0 && v < 0.0) {
                    d += k * u * v;
                    dd += k * v * v;
                }
            }
        }
        (d, dd)
    }

    /// The minimizer of the convex piecewise-quadratic objective on `[0, high]`.
    pub(super) fn minimize(&self, high: f64) -> f64 {
        let (g0, mut s_lo) = self.derivative(0.0);
        if g0 >= 0.0 {
            return 0.0;
        }
        // Within round-off of a flat derivative, the far end is the answer.
        let (mut g_hi, _) = self.derivative(high);
        if g_hi <= 1e-9 * g0.abs() {
            return high;
        }
        let (mut lo, mut hi, mut g_lo) = (0.0, high, g0);
        for _ in 0..60 {
            let mut alpha = if s_lo > 0.0 { lo - g_lo / s_lo } else { hi };
            if !(alpha > lo && alpha < hi) {
                alpha = lo - g_lo * (hi - lo) / (g_hi - g_lo);
            }
            if !(alpha > lo && alpha < hi) {
                break;
            }
            let (g, s) = self.derivative(alpha);
            if g.abs() <= 1e-14 * g0.abs() {
                return alpha;
            }
            if g < 0.0 {
                (lo, g_lo, s_lo) = (alpha, g, s);
            } else {
                (hi, g_hi) = (alpha, g);
            }
            if hi - lo <= 1e-15 * high {
                break;
            }
        }
        0.5 * (lo + hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// The objective along the line: `½ a α² + b α` of the masses and
    /// `Σ ½ k min(0, u + α v)²` of the rows' cone edges.
    fn objective(line: &Line, alpha: f64) -> f64 {
        let mut f = alpha * line.mass.0 + 0.5 * alpha * alpha * line.mass.1;
        for (r, row) in line.rows.iter().enumerate() {
            for e in 0..edges(row.friction) {
                let u = line.value[r][e] + alpha * line.slope[r][e];
                f += 0.5 * line.stiffness[r] * u.min(0.0).powi(2);
            }
        }
        f
    }

    #[test]
    fn the_minimizer_is_the_lowest_point_found_by_sampling() {
        let mut rng = StdRng::seed_from_u64(3);
        for trial in 0..200 {
            let count = rng.random_range(1..12);
            let rows: Vec<LocalRow> = (0..count)
                .map(|_| LocalRow {
                    friction: if rng.random_bool(0.5) { 0.3 } else { 0.0 },
                    ..Default::default()
                })
                .collect();
            let stiffness: Vec<f64> = (0..count)
                .map(|_| {
                    if rng.random_bool(0.2) {
                        0.0
                    } else {
                        rng.random_range(0.1..100.0)
                    }
                })
                .collect();
            let value: Vec<[f64; 2]> = (0..count)
                .map(|_| [0; 2].map(|_| rng.random_range(-1.0..1.0)))
                .collect();
            let slope: Vec<[f64; 2]> = (0..count)
                .map(|_| [0; 2].map(|_| rng.random_range(-2.0..2.0)))
                .collect();
            // Downhill at the start, as a Newton step's line is.
            let line = Line {
                rows: &rows,
                stiffness: &stiffness,
                value: &value,
                slope: &slope,
                mass: (-rng.random_range(0.0..2.0), rng.random_range(0.01..3.0)),
            };
            let high = rng.random_range(0.1..4.0);
            let alpha = line.minimize(high);
            assert!((0.0..=high).contains(&alpha), "trial {trial}: {alpha}");
            let best = (0..=20_000)
                .map(|i| objective(&line, high * i as f64 / 20_000.0))
                .fold(f64::INFINITY, f64::min);
            let found = objective(&line, alpha);
            assert!(
                found <= best + 1e-12 * (1.0 + best.abs()),
                "trial {trial}: {found} at {alpha} against {best} sampled"
            );
        }
    }
}
