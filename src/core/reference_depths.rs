//! The reference depths `zeta*` of a photo taken with any camera, from the object's 3D model
//! and the points' pixels in the photo. The invariant law needs them up to one positive scale
//! (sec. 4.1; the scale only sets the speed of the translation), and with a metric model these
//! are the depths in metres:
//!
//! - `n >= 6` points not on one plane: a DLT resection ([`resect`]) gives
//!   `P = lambda K [R | t]`; the third row of any `K` is `(0, 0, 1)`, so the third row of `P` is
//!   `lambda (r_3, t_z)` with `|r_3| = 1`, and `Z_k = P_3 (X_k, 1) / |P_3[:3]|` (sign chosen
//!   positive): no intrinsics needed.
//! - `n >= 4` points on one plane (a printed target): the plane's homography
//!   `H = lambda K [r_1 r_2 t]` (normalised DLT) in a frame of the plane; with the photo's
//!   camera matrix `K`, `|K^-1 h_1| = |K^-1 h_2| = |lambda|` and
//!   `Z_k = (K^-1 H (x_k, y_k, 1))_3 / lambda`.
//!
//! Pixels are of the ideal pinhole image: undistort a photo's points first.

use nalgebra::{DMatrix, Matrix3, SymmetricEigen, Vector3};

use crate::core::depth::{normalise_2d, resect};
use crate::error::{Error, Result, check_finite_points, check_finite_rows, check_overflow};

/// Below this ratio of the object's thinnest extent to its widest, its points are on a plane.
pub const PLANAR_THICKNESS: f64 = 1e-6;

/// Below this ratio of singular values the homography counts as degenerate.
const DEGENERATE: f64 = 1e-10;

const HOMOGRAPHY: (&str, &str) = ("plane homography (DLT)", "three of the points are on one line in the photo");

/// The depths of `points` (the object's model, `(n, 3)` in any frame, metres) in the photo
/// where they are seen at `pixels`: see the module documentation. `k` (the photo's camera
/// matrix) is needed only when the points are on one plane; a planar object without it, too
/// few points, or a point behind the camera are refused.
pub fn reference_depths(points: &[[f64; 3]], pixels: &[[f64; 2]], k: Option<&Matrix3<f64>>) -> Result<Vec<f64>> {
    check_finite_rows("object_points", points)?;
    check_finite_points("reference_pixels", pixels)?;
    if pixels.len() != points.len() {
        let expected = "one pixel per object point".to_string();
        let got = format!("{} object points, {} pixels", points.len(), pixels.len());
        return Err(Error::Shape { what: "object_points, reference_pixels", expected, got });
    }
    if points.len() < 4 {
        let why = "4 on one plane with K, 6 in relief without";
        return Err(Error::TooFewPoints { needed: 4, got: points.len(), why });
    }
    let x: Vec<Vector3<f64>> = points.iter().map(|p| Vector3::from(*p)).collect();
    let depths = match plane_frame(&x) {
        Some(frame) => {
            let k = k.ok_or(Error::InvalidParameter {
                name: "K",
                reason: "object_points are on one plane: their depths need the photo's camera matrix K".into(),
            })?;
            plane_depths(&frame, pixels, k)?
        }
        None => model_depths(&x, pixels)?,
    };
    check_overflow("object_points, reference_pixels", "depths", &[&depths])?;
    if let Some(index) = depths.iter().position(|z| !(*z > 0.0)) {
        return Err(Error::PointBehindCamera { index, depth: depths[index] });
    }
    Ok(depths)
}

/// Depths from a DLT resection of `n >= 6` points not on one plane, sign chosen positive.
fn model_depths(x: &[Vector3<f64>], pixels: &[[f64; 2]]) -> Result<Vec<f64>> {
    if x.len() < 6 {
        return Err(Error::TooFewPoints {
            needed: 6,
            got: x.len(),
            why: "a resection of an object not on one plane (4 on a plane, with K)",
        });
    }
    let p = resect(x, pixels)?;
    let row = p.row(2);
    let scale = row.columns(0, 3).norm();
    let z: Vec<f64> = x.iter().map(|x| (row[0] * x.x + row[1] * x.y + row[2] * x.z + row[3]) / scale).collect();
    Ok(positive(z))
}

/// The points' coordinates in a frame of their plane, or None when they are not on one.
fn plane_frame(x: &[Vector3<f64>]) -> Option<Vec<[f64; 2]>> {
    let n = x.len().max(1) as f64;
    let c = x.iter().sum::<Vector3<f64>>() / n;
    let scatter = x.iter().fold(Matrix3::zeros(), |s, p| s + (p - c) * (p - c).transpose());
    let eigen = SymmetricEigen::new(scatter);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    let widest = eigen.eigenvalues[order[0]].max(0.0).sqrt();
    let thinnest = eigen.eigenvalues[order[2]].max(0.0).sqrt();
    if !(thinnest <= PLANAR_THICKNESS * widest) {
        return None;
    }
    let (e1, e2) = (eigen.eigenvectors.column(order[0]), eigen.eigenvectors.column(order[1]));
    Some(x.iter().map(|p| [(p - c).dot(&e1), (p - c).dot(&e2)]).collect())
}

/// Depths of points on a plane, `plane` their coordinates in it, from the homography.
fn plane_depths(plane: &[[f64; 2]], pixels: &[[f64; 2]], k: &Matrix3<f64>) -> Result<Vec<f64>> {
    if plane.len() < 4 {
        return Err(Error::TooFewPoints { needed: 4, got: plane.len(), why: "the homography of a planar object" });
    }
    let h = homography(plane, pixels)?;
    let k_inv = k.try_inverse().ok_or_else(|| Error::InvalidIntrinsics { reason: "K is singular".into() })?;
    let m = k_inv * h;
    let lambda = (m.column(0).norm() + m.column(1).norm()) / 2.0;
    let z: Vec<f64> = plane.iter().map(|q| (m * Vector3::new(q[0], q[1], 1.0)).z / lambda).collect();
    Ok(positive(z))
}

/// `H` with `pixel ~ H (x, y, 1)`, by the normalised DLT (at least 4 points, no 3 on a line).
fn homography(plane: &[[f64; 2]], pixels: &[[f64; 2]]) -> Result<Matrix3<f64>> {
    let (t1, t2) = (normalise_2d(plane), normalise_2d(pixels));
    let n = plane.len();
    // At least 9 rows: the thin SVD of a wider matrix would drop the null vector.
    let mut a = DMatrix::zeros((2 * n).max(9), 9);
    for (i, (q, p)) in plane.iter().zip(pixels).enumerate() {
        let x = t1 * Vector3::new(q[0], q[1], 1.0);
        let u = t2 * Vector3::new(p[0], p[1], 1.0);
        for j in 0..3 {
            a[(2 * i, 3 + j)] = -x[j];
            a[(2 * i, 6 + j)] = u.y * x[j];
            a[(2 * i + 1, j)] = x[j];
            a[(2 * i + 1, 6 + j)] = -u.x * x[j];
        }
    }
    check_overflow("object_points, reference_pixels", "normalised homography system", &[a.as_slice()])?;
    let svd = a.svd(false, true);
    let v_t =
        svd.v_t.as_ref().ok_or(Error::DegenerateEstimate { what: HOMOGRAPHY.0, ratio: 0.0, hint: HOMOGRAPHY.1 })?;
    let mut order: Vec<usize> = (0..9).collect();
    order.sort_by(|&x, &y| svd.singular_values[y].total_cmp(&svd.singular_values[x]));
    let ratio = svd.singular_values[order[7]] / svd.singular_values[order[0]].max(f64::MIN_POSITIVE);
    if !(ratio > DEGENERATE) {
        return Err(Error::DegenerateEstimate { what: HOMOGRAPHY.0, ratio, hint: HOMOGRAPHY.1 });
    }
    let h_n = Matrix3::from_row_iterator(v_t.row(order[8]).iter().copied());
    let t2_inv =
        t2.try_inverse().ok_or(Error::DegenerateEstimate { what: HOMOGRAPHY.0, ratio: 0.0, hint: HOMOGRAPHY.1 })?;
    Ok(t2_inv * h_n * t1)
}

/// The depths with the sign that makes their sum positive (the projective scale's sign is free).
fn positive(mut z: Vec<f64>) -> Vec<f64> {
    if z.iter().sum::<f64>() < 0.0 {
        z.iter_mut().for_each(|d| *d = -*d);
    }
    z
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::core::se3::exp_twist;

    /// A skewed camera looking at the object from a rotated pose: the object's points in its
    /// own frame, their pixels and true depths (computed directly, `K (R X + t)`).
    fn photo(points: &[[f64; 3]]) -> (Matrix3<f64>, Vec<[f64; 2]>, Vec<f64>) {
        let k = Matrix3::new(810.0, 3.0, 330.0, 0.0, 790.0, 250.0, 0.0, 0.0, 1.0);
        let pose = exp_twist(&[0.05, -0.03, 0.7, 0.3, -0.2, 0.4]).unwrap();
        let (mut px, mut z) = (Vec::new(), Vec::new());
        for p in points {
            let c = pose.transform_point(&nalgebra::Point3::from(Vector3::from(*p)));
            let h = k * c.coords;
            px.push([h.x / h.z, h.y / h.z]);
            z.push(c.z);
        }
        (k, px, z)
    }

    fn close(a: &[f64], b: &[f64], tol: f64) {
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert!((x - y).abs() <= tol * y.abs(), "point {i}: {x} vs {y}");
        }
    }

    const RELIEF: [[f64; 3]; 7] = [
        [-0.1, -0.08, 0.0],
        [0.12, -0.07, 0.03],
        [0.1, 0.09, -0.02],
        [-0.11, 0.1, 0.05],
        [0.0, 0.02, -0.04],
        [0.05, -0.01, 0.08],
        [-0.04, 0.05, 0.01],
    ];

    #[test]
    fn an_object_in_relief_gives_its_true_depths_without_k() {
        let (k, px, z) = photo(&RELIEF);
        close(&reference_depths(&RELIEF, &px, None).unwrap(), &z, 1e-9);
        close(&reference_depths(&RELIEF, &px, Some(&k)).unwrap(), &z, 1e-9);
    }

    #[test]
    fn a_plane_gives_its_true_depths_with_k() {
        // A tilted plane (not z = 0 in the model's frame): the frame of the plane is found.
        let tilt = exp_twist(&[0.01, 0.02, -0.03, 0.4, 0.1, -0.3]).unwrap();
        let plane: Vec<[f64; 3]> = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1], [0.03, -0.02]]
            .iter()
            .map(|q| tilt.transform_point(&nalgebra::Point3::new(q[0], q[1], 0.0)).coords.into())
            .collect();
        let (k, px, z) = photo(&plane);
        close(&reference_depths(&plane, &px, Some(&k)).unwrap(), &z, 1e-9);
        let err = reference_depths(&plane, &px, None).unwrap_err();
        assert!(err.to_string().contains("on one plane"), "{err}");
    }

    #[test]
    fn too_few_points_and_bad_shapes_are_refused_by_name() {
        let (_, px, _) = photo(&RELIEF);
        let err = reference_depths(&RELIEF[..5], &px[..5], None).unwrap_err();
        assert!(matches!(err, Error::TooFewPoints { needed: 6, got: 5, .. }), "{err}");
        let err = reference_depths(&RELIEF, &px[..6], None).unwrap_err();
        assert!(err.to_string().contains("object_points, reference_pixels"), "{err}");
        assert!(err.to_string().contains("7 object points, 6 pixels"), "{err}");
        let err = reference_depths(&[], &[], None).unwrap_err();
        assert!(matches!(err, Error::TooFewPoints { needed: 4, got: 0, .. }), "{err}");
    }
}
