//! The geometry of a ribbon along a polyline: two vertices per point, offset half the
//! width to either side along the normal of the point's tangent; texture coordinates
//! running along the length (`u`, in texture repeats) and across (`v`, 0 to 1); two
//! triangles per edge. A closed strand repeats its first point at the end, so the
//! texture runs on across the seam. Each function refills its buffer in place: after
//! the first frame nothing is allocated.

use bevy::math::DVec2;

/// Points a ribbon has vertices at, for a strand of `n` particles.
pub fn ribbon_points(n: usize, closed: bool) -> usize {
    if closed && n > 0 { n + 1 } else { n }
}

/// The unit normal at point `i` of `points`: the left perpendicular of the tangent
/// through its neighbours (one-sided at an open strand's ends).
fn normal(points: &[DVec2], closed: bool, i: usize) -> DVec2 {
    let n = points.len();
    let (before, after) = if closed {
        (points[(i + n - 1) % n], points[(i + 1) % n])
    } else {
        (points[i.saturating_sub(1)], points[(i + 1).min(n - 1)])
    };
    (after - before).normalize_or_zero().perp()
}

/// Vertex positions: left then right of each point, at depth `z`.
pub fn ribbon_positions(
    points: &[DVec2],
    closed: bool,
    width: f64,
    z: f32,
    out: &mut Vec<[f32; 3]>,
) {
    out.clear();
    let n = points.len();
    if n < 2 {
        return;
    }
    for k in 0..ribbon_points(n, closed) {
        let i = k % n;
        let offset = 0.5 * width * normal(points, closed, i);
        for side in [points[i] + offset, points[i] - offset] {
            out.push([side.x as f32, side.y as f32, z]);
        }
    }
}

/// Texture coordinates: `u` the arc length over `repeat` (the length one copy of the
/// texture covers), `v` 0 on the left and 1 on the right.
pub fn ribbon_uvs(points: &[DVec2], closed: bool, repeat: f64, out: &mut Vec<[f32; 2]>) {
    out.clear();
    let n = points.len();
    if n < 2 {
        return;
    }
    let mut length = 0.0;
    for k in 0..ribbon_points(n, closed) {
        if k > 0 {
            length += points[k % n].distance(points[k - 1]);
        }
        let u = (length / repeat) as f32;
        out.extend([[u, 0.0], [u, 1.0]]);
    }
}

/// Triangle indices: two per edge, counter-clockwise.
pub fn ribbon_indices(n: usize, closed: bool, out: &mut Vec<u32>) {
    out.clear();
    if n < 2 {
        return;
    }
    for k in 0..ribbon_points(n, closed) as u32 - 1 {
        let (l0, r0, l1, r1) = (2 * k, 2 * k + 1, 2 * k + 2, 2 * k + 3);
        out.extend([l0, r0, r1, l0, r1, l1]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_straight_ribbon_is_a_rectangle_with_its_texture_repeating_along_it() {
        let points: Vec<DVec2> = (0..4).map(|i| DVec2::new(0.1 * i as f64, 0.0)).collect();
        let (mut p, mut uv, mut idx) = (Vec::new(), Vec::new(), Vec::new());
        ribbon_positions(&points, false, 0.02, 1.0, &mut p);
        ribbon_uvs(&points, false, 0.05, &mut uv);
        ribbon_indices(points.len(), false, &mut idx);
        assert_eq!((p.len(), uv.len(), idx.len()), (8, 8, 18));
        for (k, pair) in p.chunks(2).enumerate() {
            let x = 0.1 * k as f32;
            assert!((pair[0][0] - x).abs() < 1e-7 && (pair[0][1] - 0.01).abs() < 1e-7);
            assert!((pair[1][0] - x).abs() < 1e-7 && (pair[1][1] + 0.01).abs() < 1e-7);
            assert_eq!(pair[0][2], 1.0);
        }
        // 0.3 long, a texture every 0.05: six repeats.
        assert!((uv[6][0] - 6.0).abs() < 1e-6 && uv[6][1] == 0.0 && uv[7][1] == 1.0);
        // Every triangle counter-clockwise (positive area).
        for t in idx.chunks(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| p[i as usize]);
            let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(area > 0.0, "{t:?}");
        }
    }

    #[test]
    fn a_closed_ribbon_repeats_its_first_point_and_keeps_its_width() {
        let points: Vec<DVec2> = (0..12)
            .map(|i| DVec2::from_angle(i as f64 / 12.0 * std::f64::consts::TAU))
            .collect();
        let (mut p, mut uv, mut idx) = (Vec::new(), Vec::new(), Vec::new());
        ribbon_positions(&points, true, 0.1, 0.0, &mut p);
        ribbon_uvs(&points, true, 1.0, &mut uv);
        ribbon_indices(points.len(), true, &mut idx);
        assert_eq!((p.len(), uv.len(), idx.len()), (26, 26, 72));
        assert_eq!(p[0], p[24]);
        // The texture runs on across the seam: the perimeter of the 12-gon.
        let perimeter = 12.0 * 2.0 * (std::f64::consts::PI / 12.0).sin();
        assert!((uv[24][0] as f64 - perimeter).abs() < 1e-6);
        for pair in p.chunks(2) {
            let d = ((pair[0][0] - pair[1][0]).powi(2) + (pair[0][1] - pair[1][1]).powi(2)).sqrt();
            assert!((d - 0.1).abs() < 1e-6);
        }
        // Refilled in place: the same capacity next frame.
        let capacity = p.capacity();
        ribbon_positions(&points, true, 0.1, 0.0, &mut p);
        assert_eq!(p.capacity(), capacity);
    }
}
