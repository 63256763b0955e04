//! The package's exception hierarchy, built when the module loads:
//! `VsinvError(Exception)`, `InvalidInput(VsinvError, ValueError)`,
//! `DegenerateGeometry(VsinvError, ValueError)` and `NotReady(VsinvError, RuntimeError)`.
//!
//! The only place that maps errors to Python exceptions: `impl From<crate::Error> for PyErr`
//! (so `?` converts a core error in any binding) and the binding-level [`PyError`] for input
//! refused before the core sees it. Like pydantic-core's errors, every exception carries the
//! structured fields of the error as attributes (`kind`, `argument`, `index`, `row`, `key`,
//! ...; the table [`ATTRIBUTES`]), `None` where a field does not apply; the message is the
//! error's `Display` text.

use pyo3::exceptions::{PyException, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::Error;
use crate::sim::scenario::DEPTHS_REMEDY;

static VSINV_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static INVALID_INPUT: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static DEGENERATE: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static NOT_READY: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// Every attribute an exception may carry, with its documentation. `VsinvError` sets them all
/// to `None` at class level; an exception sets those its error has.
pub(crate) const ATTRIBUTES: &[(&str, &str)] = &[
    (
        "kind",
        "str: the kind of error, snake_case: 'non_finite', 'non_finite_point', 'shape', \
         'invalid_intrinsics', 'invalid_parameter', 'invalid_argument', 'too_few_points', \
         'collinear_basis', 'point_behind_camera', 'degenerate_structure', 'degenerate_estimate', \
         'scenario', 'invalid_image', 'urdf', 'distortion', 'calibration', 'rz_singular', 'unreachable', \
         'invalid_pose', 'degenerate_motion', 'not_ready'",
    ),
    ("argument", "str: the argument or parameter at fault (e.g. 'pixels', 'gain'; an image's file path)"),
    ("index", "int: the flat index of a non-finite value, or the point (or pose) at fault"),
    ("row", "int: the row of a non-finite entry of a 2-d array (the point)"),
    ("column", "int: the column of a non-finite entry of a 2-d array (the coordinate)"),
    ("expected", "str: what size was expected, in words (e.g. '12 points', 'shape (n, 2)')"),
    ("got", "str: what size was given"),
    ("needed", "int: the fewest points the task takes"),
    ("count", "int: the number of points (or poses) given"),
    ("reason", "str: what is wrong"),
    ("basis", "tuple[int, int, int]: the basis indices of a collinear basis"),
    ("image", "str: 'current' or 'reference', the image of a collinear basis"),
    ("ratio", "float: the singular-value or area ratio that failed"),
    ("threshold", "float: the threshold the ratio was held to"),
    ("depth", "float: the depth of a point at or behind the camera"),
    ("estimate", "str: what was being estimated (a degenerate estimate)"),
    ("hint", "str: what usually causes a degenerate estimate"),
    ("key", "str: the dotted scenario key at fault (e.g. 'control.gain'); None for the whole document"),
    ("file", "str: the file at fault (a scenario, calibration or URDF file)"),
    ("field", "str: the entry of a calibration file at fault (e.g. 'camera_matrix.data')"),
    ("a_hat", "float: the vanishing coefficient of the rz law (eq. 23)"),
    ("residual", "float: the smallest position residual (metres) inverse kinematics reached for an unreachable pose"),
];

fn new_class<'py>(py: Python<'py>, name: &str, bases: Bound<'py, PyTuple>, doc: &str) -> PyResult<Bound<'py, PyType>> {
    let dict = PyDict::new(py);
    dict.set_item("__module__", "vsinv")?;
    dict.set_item("__doc__", doc)?;
    let class = py.import("builtins")?.getattr("type")?.call1((name, bases, dict))?;
    Ok(class.cast_into::<PyType>()?)
}

/// `VsinvError`, with every attribute `None` at class level and the table in its docstring.
fn base_class(py: Python<'_>) -> PyResult<Bound<'_, PyType>> {
    let mut doc = String::from(
        "Base class of every vsinv error.\n\nAttributes (None where they do not apply; the message \
         is str(err)):\n\n",
    );
    for (name, text) in ATTRIBUTES {
        doc.push_str(&format!("{name}\n    {text}\n"));
    }
    let bases = PyTuple::new(py, [py.get_type::<PyException>()])?;
    let class = new_class(py, "VsinvError", bases, &doc)?;
    for (name, _) in ATTRIBUTES {
        class.setattr(*name, py.None())?;
    }
    Ok(class)
}

/// Creates the classes and adds them to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let base = VSINV_ERROR.get_or_try_init(py, || Ok::<_, PyErr>(base_class(py)?.unbind()))?;
    let base = base.bind(py).clone();
    let invalid = INVALID_INPUT.get_or_try_init(py, || {
        let bases = PyTuple::new(py, [base.clone(), py.get_type::<PyValueError>()])?;
        let doc = "Malformed input: NaN or infinity, wrong shape or dtype, invalid intrinsics or parameters, \
                   a bad scenario, image, URDF or calibration file. Attributes: see VsinvError.";
        Ok::<_, PyErr>(new_class(py, "InvalidInput", bases, doc)?.unbind())
    })?;
    let degenerate = DEGENERATE.get_or_try_init(py, || {
        let bases = PyTuple::new(py, [base.clone(), py.get_type::<PyValueError>()])?;
        let doc = "Geometry the method cannot work with: collinear basis points, fewer than 6 points, \
                   a planar object or equal depth estimates, points at or behind the camera, robot \
                   motions that do not determine a hand-eye calibration. \
                   Attributes: see VsinvError.";
        Ok::<_, PyErr>(new_class(py, "DegenerateGeometry", bases, doc)?.unbind())
    })?;
    let not_ready = NOT_READY.get_or_try_init(py, || {
        let bases = PyTuple::new(py, [base.clone(), py.get_type::<PyRuntimeError>()])?;
        let doc = "A state read before it exists, e.g. a controller's eps before its first step \
                   (kind 'not_ready').";
        Ok::<_, PyErr>(new_class(py, "NotReady", bases, doc)?.unbind())
    })?;
    m.add("VsinvError", base)?;
    m.add("NotReady", not_ready.bind(py))?;
    m.add("InvalidInput", invalid.bind(py))?;
    m.add("DegenerateGeometry", degenerate.bind(py))?;
    Ok(())
}

/// The value of one attribute.
pub(crate) enum Value {
    Str(String),
    Int(usize),
    Float(f64),
    Basis([usize; 3]),
    /// An attribute copied from another exception.
    Object(Py<PyAny>),
}

impl Value {
    fn to_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(match self {
            Value::Str(s) => s.into_pyobject(py)?.into_any(),
            Value::Int(i) => i.into_pyobject(py)?.into_any(),
            Value::Float(x) => x.into_pyobject(py)?.into_any(),
            Value::Basis(b) => PyTuple::new(py, b)?.into_any(),
            Value::Object(o) => o.bind(py).clone(),
        })
    }
}

/// The exception class of an error.
#[derive(Clone, Copy)]
enum Class {
    InvalidInput,
    Degenerate,
    NotReady,
}

/// An exception about to be raised: class, message, kind and attributes.
pub(crate) struct PyError {
    class: Class,
    message: String,
    kind: Option<&'static str>,
    attributes: Vec<(&'static str, Value)>,
}

impl PyError {
    /// `InvalidInput(message)` without attributes.
    pub(crate) fn invalid(message: String) -> Self {
        Self { class: Class::InvalidInput, message, kind: None, attributes: Vec::new() }
    }

    /// Sets `kind`.
    pub(crate) fn kind(mut self, kind: &'static str) -> Self {
        self.kind = Some(kind);
        self
    }

    /// Sets `argument`.
    pub(crate) fn argument(self, argument: &str) -> Self {
        self.with("argument", Value::Str(argument.to_string()))
    }

    /// Sets `reason`.
    pub(crate) fn reason(self, reason: String) -> Self {
        self.with("reason", Value::Str(reason))
    }

    /// Sets one attribute (a name of [`ATTRIBUTES`]).
    pub(crate) fn with(mut self, name: &'static str, value: Value) -> Self {
        self.attributes.push((name, value));
        self
    }

    /// The error of a file: the message prefixed by its path, `file` set unless the error
    /// already names one (a calibration or URDF file that the first file names).
    pub(crate) fn in_file(mut self, file: &str) -> Self {
        self.message = format!("{file}: {}", self.message);
        if self.attributes.iter().all(|(name, _)| *name != "file") {
            self.attributes.push(("file", Value::Str(file.to_string())));
        }
        self
    }

    fn instantiate<'py>(&self, py: Python<'py>, class: &Bound<'py, PyType>) -> PyResult<Bound<'py, PyAny>> {
        let exc = class.call1((self.message.as_str(),))?;
        if let Some(kind) = self.kind {
            exc.setattr("kind", kind)?;
        }
        for (name, value) in &self.attributes {
            exc.setattr(*name, value.to_object(py)?)?;
        }
        Ok(exc)
    }
}

impl From<PyError> for PyErr {
    fn from(e: PyError) -> PyErr {
        let cell = match e.class {
            Class::InvalidInput => &INVALID_INPUT,
            Class::Degenerate => &DEGENERATE,
            Class::NotReady => &NOT_READY,
        };
        Python::attach(|py| match cell.get(py) {
            Some(class) => match e.instantiate(py, class.bind(py)) {
                Ok(exc) => PyErr::from_value(exc),
                Err(err) => err,
            },
            None => PyRuntimeError::new_err(e.message),
        })
    }
}

/// The kind and attributes of a core error (every variant: a new one fails to compile here).
fn describe(err: &Error) -> (&'static str, Vec<(&'static str, Value)>) {
    use Value::{Basis, Float, Int, Str};
    let s = |x: &str| Str(x.to_string());
    let opt = |x: &str| if x.is_empty() { None } else { Some(Str(x.to_string())) };
    match err {
        Error::NonFinite { what, index } => ("non_finite", vec![("argument", s(what)), ("index", Int(*index))]),
        Error::NonFinitePoint { what, row, column } => {
            ("non_finite_point", vec![("argument", s(what)), ("row", Int(*row)), ("column", Int(*column))])
        }
        Error::Shape { what, expected, got } => {
            ("shape", vec![("argument", s(what)), ("expected", s(expected)), ("got", s(got))])
        }
        Error::InvalidIntrinsics { reason } => ("invalid_intrinsics", vec![("reason", s(reason))]),
        Error::InvalidParameter { name, reason } => {
            ("invalid_parameter", vec![("argument", s(name)), ("reason", s(reason))])
        }
        Error::TooFewPoints { needed, got, why } => {
            ("too_few_points", vec![("needed", Int(*needed)), ("count", Int(*got)), ("reason", s(why))])
        }
        Error::CollinearBasis { basis, image, ratio } => {
            ("collinear_basis", vec![("basis", Basis(*basis)), ("image", s(image)), ("ratio", Float(*ratio))])
        }
        Error::PointBehindCamera { index, depth } => {
            ("point_behind_camera", vec![("index", Int(*index)), ("depth", Float(*depth))])
        }
        Error::DegenerateStructure { ratio, threshold } => {
            ("degenerate_structure", vec![("ratio", Float(*ratio)), ("threshold", Float(*threshold))])
        }
        Error::DegenerateEstimate { what, ratio, hint } => {
            ("degenerate_estimate", vec![("estimate", s(what)), ("ratio", Float(*ratio)), ("hint", s(hint))])
        }
        Error::Scenario { key, reason } => {
            ("scenario", opt(key).map(|k| ("key", k)).into_iter().chain([("reason", s(reason))]).collect())
        }
        Error::InvalidImage { what, reason } => ("invalid_image", vec![("argument", s(what)), ("reason", s(reason))]),
        Error::Urdf { file, message } => ("urdf", vec![("file", s(file)), ("reason", s(message))]),
        Error::Distortion { index, reason } => ("distortion", vec![("index", Int(*index)), ("reason", s(reason))]),
        Error::Calibration { file, field, reason } => {
            let field = opt(field).map(|f| ("field", f));
            ("calibration", [("file", s(file))].into_iter().chain(field).chain([("reason", s(reason))]).collect())
        }
        Error::RzSingular { a_hat } => ("rz_singular", vec![("a_hat", Float(*a_hat))]),
        Error::Unreachable { position_residual, .. } => {
            ("unreachable", vec![("argument", s("pose")), ("residual", Float(*position_residual))])
        }
        Error::InvalidPose { what, index, reason } => {
            ("invalid_pose", vec![("argument", s(what)), ("index", Int(*index)), ("reason", s(reason))])
        }
        Error::DegenerateMotion { poses, reason } => {
            ("degenerate_motion", vec![("count", Int(*poses)), ("reason", s(reason))])
        }
    }
}

impl From<&Error> for PyError {
    fn from(err: &Error) -> Self {
        let class = if err.is_degenerate() { Class::Degenerate } else { Class::InvalidInput };
        let (kind, attributes) = describe(err);
        // Python users pass depths to scenarios too: the remedy names the scenario key.
        let message = err.message_with_remedy(DEPTHS_REMEDY);
        Self { class, message, kind: Some(kind), attributes }
    }
}

/// `DegenerateGeometry` for scene geometry ([`Error::is_degenerate`]), `InvalidInput`
/// otherwise, with the error's fields as attributes: `?` on a `crate::Result` in a binding.
impl From<Error> for PyErr {
    fn from(err: Error) -> PyErr {
        PyError::from(&err).into()
    }
}

/// `NotReady(msg)`, kind `not_ready`.
pub(crate) fn not_ready(msg: &str) -> PyErr {
    PyError { class: Class::NotReady, message: msg.to_string(), kind: Some("not_ready"), attributes: Vec::new() }.into()
}

/// `InvalidInput(msg)` for input refused by the bindings that no single argument owns.
pub(crate) fn invalid_input(msg: String) -> PyErr {
    PyError::invalid(msg).into()
}

/// `InvalidInput(msg)` about one argument: kind `invalid_argument`, `argument` set.
pub(crate) fn invalid_argument(argument: &str, msg: String) -> PyErr {
    PyError::invalid(msg).kind("invalid_argument").argument(argument).into()
}

/// `InvalidInput("{argument}: expected {expected}, got {got}")`, kind `shape`, as the core's
/// `Error::Shape` for an argument the bindings read.
pub(crate) fn shape_error(argument: &str, expected: String, got: String) -> PyErr {
    let msg = format!("{argument}: expected {expected}, got {got}");
    shape_error_saying(argument, expected, got, msg)
}

/// [`shape_error`] with its own message.
pub(crate) fn shape_error_saying(argument: &str, expected: String, got: String, msg: String) -> PyErr {
    PyError::invalid(msg)
        .kind("shape")
        .argument(argument)
        .with("expected", Value::Str(expected))
        .with("got", Value::Str(got))
        .into()
}

/// `InvalidInput(msg)` carrying the attributes of `cause` (when it is a vsinv error), for an
/// error re-raised with more context (`scenario 3: ...`, `K: matrix 1: ...`); `argument`
/// replaces the cause's when given.
pub(crate) fn reraise(cause: &PyErr, msg: String, argument: Option<&str>) -> PyErr {
    Python::attach(|py| {
        let value = cause.value(py);
        let ours = VSINV_ERROR.get(py).is_some_and(|base| value.is_instance(base.bind(py)).unwrap_or(false));
        let mut err = PyError::invalid(msg);
        if ours {
            for (name, _) in ATTRIBUTES {
                if let Ok(v) = value.getattr(*name)
                    && !v.is_none()
                {
                    err = err.with(name, Value::Object(v.unbind()));
                }
            }
        } else if argument.is_some() {
            err = err.kind("invalid_argument");
        }
        if let Some(a) = argument {
            err = err.argument(a);
        }
        err.into()
    })
}
