//! The invariant of sec. 2.3 and its Jacobians (sec. 4.1): invariant points, the invariant
//! Jacobian and its factors, the rz coefficients of eq. (23), the structure ratio and the
//! choice of basis.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use super::BasisArg;
use super::arrays::{depths_arg, finite_out, from_matrix, mat, pixels_arg, points2, vec1};
use super::camera::intrinsics;
use crate::core::jacobian::check_pixels_and_depths;

/// The fewest points `invariant_jacobian` and `jacobian_factors` take (the basis and one more).
const MIN_JACOBIAN_POINTS: usize = 4;

type PixelsPair<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

/// The invariant points q_k = Q^-1 p_k of all n points (sec. 2.3), an (n, 3) array; Q is built from the three
/// `basis` points, so q does not depend on the intrinsics.
#[pyfunction]
#[pyo3(signature = (pixels, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, basis=(0, 1, 2))")]
fn invariant_points<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    basis: BasisArg,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = pixels_arg(pixels, "pixels")?;
    let px = points2(&a)?;
    let q = crate::core::invariant::invariant_points(px, basis.resolve(py, px, || Ok(()))?)?;
    finite_out("pixels", q.as_flattened())?;
    mat(py, q.len(), 3, q.into_flattened())
}

/// The invariant Jacobian J (3(n-3), 5) of sec. 4.1 at the given pixels and depths: the motion of the non-basis
/// invariant points per unit of (vx, vy, vz, wx, wy).
#[pyfunction]
#[pyo3(signature = (pixels, depths, K, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, K, basis=(0, 1, 2))")]
#[allow(non_snake_case)]
fn invariant_jacobian<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    basis: BasisArg,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let k = intrinsics(K, "K")?;
    let z = z.as_slice()?;
    let basis = basis.resolve(py, px, || check_pixels_and_depths(px, z, MIN_JACOBIAN_POINTS))?;
    let j = crate::core::jacobian::invariant_jacobian(px, z, &k, basis)?;
    finite_out("pixels, depths, K", j.as_slice())?;
    from_matrix(py, &j)
}

/// The factors (Phi (3(n-3), 3), Psi (3(n-3), 2)) of sec. 4.1, with J = [Phi K, Psi F(K)].
#[pyfunction]
#[pyo3(signature = (pixels, depths, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, basis=(0, 1, 2))")]
fn jacobian_factors<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    basis: BasisArg,
) -> PyResult<PixelsPair<'py>> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let z = z.as_slice()?;
    let basis = basis.resolve(py, px, || check_pixels_and_depths(px, z, MIN_JACOBIAN_POINTS))?;
    let (phi, psi) = crate::core::jacobian::jacobian_factors(px, z, basis)?;
    finite_out("pixels, depths", phi.as_slice())?;
    finite_out("pixels, depths", psi.as_slice())?;
    Ok((from_matrix(py, &phi)?, from_matrix(py, &psi)?))
}

/// The coefficients (a, c (5,)) of eq. (23): d eps_z/dt = a w_z + c . (vx, vy, vz, wx, wy).
#[pyfunction]
#[allow(non_snake_case)]
#[pyo3(signature = (pixels, depths, reference_pixels, K, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, reference_pixels, K, basis=(0, 1, 2))")]
fn rz_coefficients<'py>(
    py: Python<'py>,
    pixels: &Bound<'py, PyAny>,
    depths: &Bound<'py, PyAny>,
    reference_pixels: &Bound<'py, PyAny>,
    K: &Bound<'py, PyAny>,
    basis: BasisArg,
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>)> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let r = pixels_arg(reference_pixels, "reference_pixels")?;
    let (px, rpx) = (points2(&a)?, points2(&r)?);
    let k = intrinsics(K, "K")?;
    let z = z.as_slice()?;
    let basis = basis.resolve(py, rpx, || {
        check_pixels_and_depths(px, z, 3)?;
        crate::error::check_finite_points("reference_pixels", rpx)?;
        match rpx.len() == px.len() {
            true => Ok(()),
            false => Err(crate::Error::Shape {
                what: "reference_pixels",
                expected: format!("{} points", px.len()),
                got: format!("{} points", rpx.len()),
            }),
        }
    })?;
    let (coef_a, c) = crate::core::jacobian::rz_coefficients(px, z, rpx, &k, basis)?;
    finite_out("pixels, depths, reference_pixels, K", &[coef_a])?;
    finite_out("pixels, depths, reference_pixels, K", c.as_slice())?;
    Ok((coef_a, vec1(py, c.as_slice())))
}

/// sigma_5/sigma_1 of the depth-balanced invariant Jacobian: near 0 for a degenerate structure (a planar object,
/// equal depths), where the law cannot tell motions apart.
#[pyfunction]
#[pyo3(signature = (pixels, depths, K, basis = BasisArg::Fixed([0, 1, 2])), text_signature = "(pixels, depths, K, basis=(0, 1, 2))")]
#[allow(non_snake_case)]
fn structure_ratio(
    py: Python<'_>,
    pixels: &Bound<'_, PyAny>,
    depths: &Bound<'_, PyAny>,
    K: &Bound<'_, PyAny>,
    basis: BasisArg,
) -> PyResult<f64> {
    let (a, z) = (pixels_arg(pixels, "pixels")?, depths_arg(depths)?);
    let px = points2(&a)?;
    let k = intrinsics(K, "K")?;
    let z = z.as_slice()?;
    let basis = basis.resolve(py, px, || check_pixels_and_depths(px, z, crate::core::jacobian::MIN_POINTS))?;
    let r = crate::core::jacobian::structure_ratio(px, z, &k, basis)?;
    finite_out("pixels, depths, K", &[r])?;
    Ok(r)
}

/// Three points well spread in the image (the widest triangle; among equal areas the first
/// (i, j, k) in index order), sorted. O(n log n); refuses (InvalidInput, `pixels`) point sets
/// with more than 10,000 convex-hull vertices. Runs without the GIL.
#[pyfunction]
fn choose_basis(py: Python<'_>, pixels: &Bound<'_, PyAny>) -> PyResult<(usize, usize, usize)> {
    let a = pixels_arg(pixels, "pixels")?;
    let [i, j, k] = super::args::choose_basis_detached(py, points2(&a)?)?;
    Ok((i, j, k))
}

/// Adds the invariant, its Jacobians and `choose_basis`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(invariant_points, m)?)?;
    m.add_function(wrap_pyfunction!(invariant_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(structure_ratio, m)?)?;
    m.add_function(wrap_pyfunction!(jacobian_factors, m)?)?;
    m.add_function(wrap_pyfunction!(rz_coefficients, m)?)?;
    m.add_function(wrap_pyfunction!(choose_basis, m)?)?;
    Ok(())
}
