//! The elements of a `<transform>`, as matrices. Mitsuba composes them in file order, each new
//! one multiplied on the left (`M = op_n * ... * op_1`), with column vectors (`p' = M p`).

use glam::{DMat3, DMat4, DVec3};

/// A translation by `v`.
pub fn translate(v: DVec3) -> DMat4 {
    DMat4::from_translation(v)
}

/// A rotation by `angle` degrees about `axis` (normalised here), right-handed: Mitsuba's
/// `Transform::rotate`. `None` for a zero axis, which Mitsuba refuses.
pub fn rotate(axis: DVec3, angle_degrees: f64) -> Option<DMat4> {
    let axis = axis.try_normalize()?;
    Some(DMat4::from_axis_angle(axis, angle_degrees.to_radians()))
}

/// A scale by `v` per axis.
pub fn scale(v: DVec3) -> DMat4 {
    DMat4::from_scale(v)
}

/// A matrix given as 16 values (4 x 4, row by row) or 9 (the upper-left 3 x 3, row by row, the
/// rest as in the identity). `None` for another count.
pub fn matrix(values: &[f64]) -> Option<DMat4> {
    match values.len() {
        // glam reads columns; the file gives rows.
        16 => Some(DMat4::from_cols_slice(values).transpose()),
        9 => Some(DMat4::from_mat3(DMat3::from_cols_slice(values).transpose())),
        _ => None,
    }
}

/// Mitsuba's `coordinate_system(n)`: two unit vectors that make an orthonormal basis with the
/// unit vector `n` (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
pub fn coordinate_system(n: DVec3) -> (DVec3, DVec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let mulsign = |v: f64, s: f64| if s >= 0.0 { v } else { -v };
    (
        DVec3::new(mulsign(n.x * n.x * a, n.z) + 1.0, mulsign(b, n.z), -mulsign(n.x, n.z)),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Mitsuba's `Transform::look_at`: the camera-to-world matrix of a camera at `origin` looking
/// at `target`, with its x axis `normalize(up x dir)` (to the left of the picture), its y axis
/// the corrected up and its z axis the viewing direction. A zero `up` is replaced by a vector
/// perpendicular to the direction (as Mitsuba does). `None` when it is degenerate (`target` at
/// `origin`, `up` along the direction).
pub fn look_at(origin: DVec3, target: DVec3, up: DVec3) -> Option<DMat4> {
    let dir = (target - origin).try_normalize()?;
    let up = if up == DVec3::ZERO { coordinate_system(dir).0 } else { up };
    let left = up.cross(dir).try_normalize()?;
    let new_up = dir.cross(left);
    let m = DMat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0));
    m.is_finite().then_some(m)
}

/// Whether `m` cannot be inverted (or holds a non-finite number).
pub fn is_singular(m: &DMat4) -> bool {
    let det = m.determinant();
    !m.is_finite() || !det.is_finite() || det.abs() < f64::MIN_POSITIVE
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DMat4, b: DMat4) {
        assert!(a.abs_diff_eq(b, 1e-12), "{a}\nvs\n{b}");
    }

    #[test]
    fn rotation_is_right_handed_in_degrees() {
        let r = rotate(DVec3::new(0.0, 0.0, 2.0), 90.0).expect("axis");
        assert!(r.transform_point3(DVec3::X).abs_diff_eq(DVec3::Y, 1e-12));
        assert!(rotate(DVec3::ZERO, 10.0).is_none());
    }

    #[test]
    fn matrices_are_read_row_by_row() {
        let m = matrix(&[1., 0., 0., 5., 0., 1., 0., 6., 0., 0., 1., 7., 0., 0., 0., 1.]).expect("16");
        close(m, translate(DVec3::new(5.0, 6.0, 7.0)));
        let m3 = matrix(&[0., -1., 0., 1., 0., 0., 0., 0., 1.]).expect("9");
        close(m3, rotate(DVec3::Z, 90.0).expect("axis"));
        assert!(matrix(&[1.0; 12]).is_none());
    }

    #[test]
    fn look_at_matches_mitsuba() {
        // Mitsuba: look_at((0,0,5), (0,0,0), (0,1,0)) has columns (-1,0,0), (0,1,0), (0,0,-1).
        let m = look_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y).expect("valid");
        let expected =
            DMat4::from_cols_array(&[-1., 0., 0., 0., 0., 1., 0., 0., 0., 0., -1., 0., 0., 0., 5., 1.]);
        close(m, expected);
        assert!(look_at(DVec3::ONE, DVec3::ONE, DVec3::Y).is_none());
        assert!(look_at(DVec3::ZERO, DVec3::Y, DVec3::Y).is_none());
        // A zero up is replaced by one perpendicular to the direction.
        let m = look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), DVec3::ZERO).expect("valid");
        assert!(!is_singular(&m));
    }

    #[test]
    fn coordinate_systems_are_orthonormal() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(1.0, 2.0, 3.0).normalize(),
            DVec3::new(0.3, -0.2, -0.9).normalize(),
        ] {
            let (s, t) = coordinate_system(n);
            assert!((s.length() - 1.0).abs() < 1e-12 && (t.length() - 1.0).abs() < 1e-12);
            assert!(s.dot(t).abs() < 1e-12 && s.dot(n).abs() < 1e-12 && t.dot(n).abs() < 1e-12);
        }
    }

    #[test]
    fn singular_matrices_are_found() {
        assert!(is_singular(&scale(DVec3::new(1.0, 0.0, 1.0))));
        assert!(is_singular(&DMat4::from_cols_array(&[f64::NAN; 16])));
        assert!(!is_singular(&scale(DVec3::splat(1e-3))));
    }
}
