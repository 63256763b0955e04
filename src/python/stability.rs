//! Stability of the invariant law (sec. 5): Props. 1-3 for a camera or a schedule of cameras.

use nalgebra::Matrix3;
use numpy::{Complex64, PyArray1, PyArrayMethods};
use pyo3::prelude::*;

use super::arrays::f64_array;
use super::camera::{PyIntrinsics, intrinsics, matrix3};
use super::control::bool_repr;
use super::errors::{PyError, Value, invalid_argument, reraise};
use crate::core::stability::{StabilityReport, check_upper_triangular};
use crate::error::fixed_or_short;

/// Stability verdicts of Props. 1-2 and the sigma of Prop. 3.
#[pyclass(name = "StabilityReport", module = "vsinv._core", frozen)]
struct PyStabilityReport {
    inner: StabilityReport,
    single: bool,
}

#[pymethods]
impl PyStabilityReport {
    /// Prop. 1 (constant K): necessary and sufficient.
    #[getter]
    fn prop1(&self) -> bool {
        self.inner.prop1
    }
    /// Prop. 2 (K varying over the schedule): sufficient.
    #[getter]
    fn prop2(&self) -> bool {
        self.inner.prop2
    }
    /// Smallest eigenvalue of A + A^T over the schedule (Prop. 3's sigma when positive).
    #[getter]
    fn sigma(&self) -> f64 {
        self.inner.sigma
    }
    /// Eigenvalues of A: complex (5,) for one K, (m, 5) for a schedule of m matrices.
    #[getter]
    fn eigenvalues<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let flat: Vec<Complex64> =
            self.inner.eigenvalues.iter().flatten().map(|c| Complex64::new(c.re, c.im)).collect();
        let arr = PyArray1::from_vec(py, flat);
        if self.single { Ok(arr.into_any()) } else { Ok(arr.reshape([self.inner.eigenvalues.len(), 5])?.into_any()) }
    }
    /// Prop. 3: the bound psi/phi on ||eps|| when ||b(t)|| <= max_b; InvalidInput when
    /// Prop. 2 fails (sigma <= 0: no bound).
    fn tracking_bound(&self, max_b: f64) -> PyResult<f64> {
        Ok(self.inner.tracking_bound(max_b)?)
    }
    fn __repr__(&self) -> String {
        format!(
            "StabilityReport(prop1={}, prop2={}, sigma={})",
            bool_repr(self.inner.prop1),
            bool_repr(self.inner.prop2),
            fixed_or_short(self.inner.sigma, 6)
        )
    }
}

/// Reads K as one camera (Intrinsics or (3, 3)) or a schedule ((m, 3, 3) or a list).
fn k_schedule(obj: &Bound<'_, PyAny>) -> PyResult<(Vec<Matrix3<f64>>, bool)> {
    if let Ok(k) = obj.cast::<PyIntrinsics>() {
        return Ok((vec![k.get().inner.matrix()], true));
    }
    if let Ok(list) = obj.cast::<pyo3::types::PyList>()
        && list.iter().any(|x| x.cast::<PyIntrinsics>().is_ok())
    {
        let ks = list
            .iter()
            .enumerate()
            .map(|(m, x)| {
                intrinsics(&x, "K")
                    .map(|k| k.matrix())
                    .map_err(|e| reraise(&e, format!("K: matrix {m}: {}", e.value(x.py())), Some("K")))
            })
            .collect::<PyResult<_>>()?;
        return Ok((ks, false));
    }
    let a = f64_array(obj, "K", &[None, Some(3), Some(3)]).or_else(|_| f64_array(obj, "K", &[Some(3), Some(3)]));
    let a = a.map_err(|_| {
        invalid_argument("K", "K: expected an Intrinsics, a (3, 3) array or an (m, 3, 3) schedule".into())
    })?;
    let single = a.shape().len() == 2;
    for (m, k) in a.as_slice()?.chunks_exact(9).enumerate() {
        if let Some(i) = k.iter().position(|x| !x.is_finite()) {
            let at = if single { "at ".to_string() } else { format!("in matrix {m}, ") };
            let msg = format!("K: non-finite value {at}row {}, column {}", i / 3, i % 3);
            let (row, column) = (Value::Int(i / 3), Value::Int(i % 3));
            return Err(PyError::invalid(msg)
                .kind("non_finite_point")
                .argument("K")
                .with("row", row)
                .with("column", column)
                .into());
        }
    }
    let ks = a.as_slice()?.chunks_exact(9).map(Matrix3::from_row_slice).collect();
    Ok((ks, single))
}

/// Props. 1-2 for the true intrinsics `K` (one camera, or a schedule of cameras), an estimate `K_hat` (a 3x3
/// upper-triangular matrix or Intrinsics), the depth scale `kappa` and the gain.
#[pyfunction]
#[pyo3(signature = (K, K_hat, kappa = 1.0, gain = 1.0), text_signature = "(K, K_hat, kappa=1.0, gain=1.0)")]
#[allow(non_snake_case)]
fn check_stability(
    K: &Bound<'_, PyAny>,
    K_hat: &Bound<'_, PyAny>,
    kappa: f64,
    gain: f64,
) -> PyResult<PyStabilityReport> {
    let (ks, single) = k_schedule(K)?;
    let k_hat = match K_hat.cast::<PyIntrinsics>() {
        Ok(i) => i.get().inner.matrix(),
        Err(_) => matrix3(K_hat, "K_hat")?,
    };
    check_upper_triangular("K_hat", &k_hat)?;
    let inner = crate::core::stability::check_stability(&ks, &k_hat, kappa, gain)?;
    Ok(PyStabilityReport { inner, single })
}

/// The bound psi/phi = 2 max_b / (gain sigma) of Prop. 3 (eq. 20) on ||eps|| while ||b(t)|| <= max_b;
/// `InvalidInput` for gain <= 0, sigma <= 0 (Prop. 2 fails: no bound), max_b < 0 or a bound that overflows.
#[pyfunction]
fn tracking_bound(gain: f64, sigma: f64, max_b: f64) -> PyResult<f64> {
    Ok(crate::core::stability::tracking_bound(gain, sigma, max_b)?)
}

/// Adds `StabilityReport`, `check_stability` and `tracking_bound`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyStabilityReport>()?;
    m.add_function(wrap_pyfunction!(check_stability, m)?)?;
    m.add_function(wrap_pyfunction!(tracking_bound, m)?)?;
    Ok(())
}
