//! The package's exception hierarchy, built when the module loads:
//! `VsinvError(Exception)`, `InvalidInput(VsinvError, ValueError)`,
//! `DegenerateGeometry(VsinvError, ValueError)` and `NotReady(VsinvError, RuntimeError)`.
//!
//! The only place that maps errors to Python exceptions: `impl From<E> for PyErr` for the error
//! of every layer (the core's `Error`, `VisionError`, `CalibrationError`, `SimError`; so `?`
//! converts any of them in any binding), all through one function, `py_error`, which takes the
//! class, the location and the message from the error's [`Located`] answers and the kind and
//! attributes from its layer's `describe_*` (a wrapped lower error is described by its own
//! layer's); and the binding-level [`PyError`] for input refused before the core sees it.
//! Like pydantic-core's errors, every exception carries the structured fields of the error as
//! attributes (`kind`, `argument`, `index`, `row`, `key`, ...; the table [`ATTRIBUTES`]),
//! `None` where a field does not apply; the message is the error's `Display` text.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::calibration::CalibrationError;
use crate::error::{Error, Located};
use crate::location::Step;
use crate::sim::SimError;
use crate::sim::scenario::DEPTHS_REMEDY;
use crate::vision::VisionError;

static VSINV_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static INVALID_INPUT: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static DEGENERATE: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static NOT_READY: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// One exception class: its name, its parent in the hierarchy (None: the root), the Python
/// built-in exception it also derives from, and its docstring.
pub(crate) struct ClassSpec {
    pub(crate) name: &'static str,
    pub(crate) parent: Option<&'static str>,
    pub(crate) builtin: &'static str,
    pub(crate) doc: &'static str,
}

/// The exception classes, declared once: the module builds them from this table, Python sees it
/// as `ERROR_CLASSES`, and a test checks the stub's classes and docstrings against it.
pub(crate) const CLASSES: [ClassSpec; 4] = [
    ClassSpec {
        name: "VsinvError",
        parent: None,
        builtin: "Exception",
        doc: "Base class of every vsinv error.\n\nThe structured fields of the error are attributes, None where \
              they do not apply (and on exceptions raised by Python code); match on them rather than on the \
              message.",
    },
    ClassSpec {
        name: "InvalidInput",
        parent: Some("VsinvError"),
        builtin: "ValueError",
        doc: "Malformed input: NaN or infinity, wrong shape or dtype, invalid intrinsics or parameters, a bad \
              scenario, image, URDF or calibration file.",
    },
    ClassSpec {
        name: "DegenerateGeometry",
        parent: Some("VsinvError"),
        builtin: "ValueError",
        doc: "Geometry the method cannot work with: collinear basis points, too few points, a planar object or \
              equal depth estimates, points at or behind the camera, robot motions that do not determine a \
              hand-eye calibration.",
    },
    ClassSpec {
        name: "NotReady",
        parent: Some("VsinvError"),
        builtin: "RuntimeError",
        doc: "A state read before it exists, e.g. a controller's eps before its first step (kind 'not_ready').",
    },
];

/// Every `kind` an exception carries: the kind, the class raised with it, and its meaning. The
/// kinds of core errors are [`describe`]'s (a test checks each variant's kind is here with its
/// class); `invalid_argument` and `not_ready` are the bindings' own.
pub(crate) const KINDS: &[(&str, &str, &str)] = &[
    ("non_finite", "InvalidInput", "a NaN or infinite value in an array"),
    ("non_finite_point", "InvalidInput", "a NaN or infinite entry of a 2-d array (a point)"),
    ("shape", "InvalidInput", "an array of the wrong size or shape"),
    ("invalid_intrinsics", "InvalidInput", "intrinsics that are not a camera's"),
    ("invalid_parameter", "InvalidInput", "a parameter out of its domain"),
    ("invalid_argument", "InvalidInput", "an argument the bindings refuse (a name, a type, a combination)"),
    ("too_few_points", "DegenerateGeometry", "fewer points than the task takes"),
    ("collinear_basis", "DegenerateGeometry", "the three basis points on a line"),
    ("point_behind_camera", "DegenerateGeometry", "a point at or behind the camera"),
    ("degenerate_structure", "DegenerateGeometry", "a planar object or equal depths"),
    ("degenerate_estimate", "DegenerateGeometry", "an estimate the data do not determine"),
    ("scenario", "InvalidInput", "a bad scenario"),
    ("invalid_image", "InvalidInput", "an image that cannot be used"),
    ("urdf", "InvalidInput", "a bad URDF file"),
    ("distortion", "InvalidInput", "bad lens distortion coefficients"),
    ("calibration", "InvalidInput", "a bad calibration file"),
    ("rz_singular", "DegenerateGeometry", "the rz law's coefficient vanishes (eq. 23)"),
    ("unreachable", "InvalidInput", "a pose the arm cannot reach"),
    ("invalid_pose", "InvalidInput", "a pose that is not a rigid motion"),
    ("degenerate_motion", "DegenerateGeometry", "robot motions that do not determine a hand-eye calibration"),
    ("not_ready", "NotReady", "a state read before it exists"),
];

/// Every attribute an exception may carry: name, Python type and documentation. `VsinvError`
/// sets them all to `None` at class level; an exception sets those its error has.
pub(crate) const ATTRIBUTES: &[(&str, &str, &str)] = &[
    ("kind", "str", "The kind of error, one of ERROR_KINDS:"),
    ("argument", "str", "The argument or parameter at fault ('pixels', 'gain', ...; an image's file path)."),
    ("index", "int", "The flat index of a non-finite value, or the point (or pose) at fault."),
    ("row", "int", "The row (point) of a non-finite entry of a 2-d array."),
    ("column", "int", "The column (coordinate) of a non-finite entry of a 2-d array."),
    ("expected", "str", "The size expected, in words ('12 points', 'shape (n, 2)')."),
    ("got", "str", "The size given."),
    ("needed", "int", "The fewest points the task takes."),
    ("count", "int", "The number of points (or poses) given."),
    ("reason", "str", "What is wrong."),
    ("basis", "tuple[int, int, int]", "The basis indices of a collinear basis."),
    ("image", "str", "'current' or 'reference': the image of a collinear basis."),
    ("ratio", "float", "The singular-value or area ratio that failed."),
    ("threshold", "float", "The threshold the ratio was held to."),
    ("depth", "float", "The depth of a point at or behind the camera."),
    ("estimate", "str", "What was being estimated (a degenerate estimate)."),
    ("hint", "str", "What usually causes a degenerate estimate."),
    ("key", "str", "The dotted scenario key at fault ('control.gain'); None for the whole document."),
    (
        "location",
        "tuple[str | int, ...]",
        "Where the error is, as data: keys and indices from the input's root, as the message names it \
         (('control', 'gain'), ('pixels', 4, 1), ('object', 'points', 2); () for a whole scenario).",
    ),
    ("file", "str", "The file at fault (a scenario, calibration or URDF file)."),
    ("field", "str", "The entry of a calibration file at fault ('camera_matrix.data')."),
    ("a_hat", "float", "The vanishing coefficient of the rz law (eq. 23)."),
    ("residual", "float", "The smallest position residual (m) inverse kinematics reached for an unreachable pose."),
];

fn new_class<'py>(py: Python<'py>, name: &str, bases: Bound<'py, PyTuple>, doc: &str) -> PyResult<Bound<'py, PyType>> {
    let dict = PyDict::new(py);
    dict.set_item("__module__", "vsinv")?;
    dict.set_item("__doc__", doc)?;
    let class = py.import("builtins")?.getattr("type")?.call1((name, bases, dict))?;
    Ok(class.cast_into::<PyType>()?)
}

/// The docstring of a class at run time: the table's, and for the root the attributes with
/// their types and meanings.
fn runtime_doc(spec: &ClassSpec) -> String {
    let mut doc = spec.doc.to_string();
    if spec.parent.is_none() {
        doc.push_str("\n\nAttributes (None where they do not apply; the message is str(err)):\n\n");
        for (name, kind, _) in ATTRIBUTES {
            doc.push_str(&format!("{name}\n    {kind}: {}\n", attribute_doc(name)));
        }
    } else {
        doc.push_str(" Attributes: see VsinvError.");
    }
    doc
}

/// The documentation of the attribute `name`; that of `kind` lists the kinds.
fn attribute_doc(name: &str) -> String {
    let text = ATTRIBUTES.iter().find(|(n, _, _)| *n == name).map_or("", |(_, _, d)| d);
    if name != "kind" {
        return text.to_string();
    }
    let kinds: Vec<String> = KINDS.iter().map(|(k, _, _)| format!("'{k}'")).collect();
    format!("{text} {}.", kinds.join(", "))
}

/// The cell holding the class named `name`.
fn cell(name: &str) -> Option<&'static PyOnceLock<Py<PyType>>> {
    match name {
        "VsinvError" => Some(&VSINV_ERROR),
        "InvalidInput" => Some(&INVALID_INPUT),
        "DegenerateGeometry" => Some(&DEGENERATE),
        "NotReady" => Some(&NOT_READY),
        _ => None,
    }
}

/// One class of [`CLASSES`], its parent made first; with every attribute `None` at the root.
fn make_class<'py>(py: Python<'py>, spec: &ClassSpec) -> PyResult<Bound<'py, PyType>> {
    let missing = || PyRuntimeError::new_err(format!("no cell for the exception class {}", spec.name));
    let builtin = py.import("builtins")?.getattr(spec.builtin)?;
    let bases = match spec.parent {
        Some(parent) => {
            let parent = cell(parent).and_then(|c| c.get(py)).ok_or_else(missing)?;
            PyTuple::new(py, [parent.bind(py).clone().into_any(), builtin])?
        }
        None => PyTuple::new(py, [builtin])?,
    };
    let class = new_class(py, spec.name, bases, &runtime_doc(spec))?;
    if spec.parent.is_none() {
        for (name, _, _) in ATTRIBUTES {
            class.setattr(*name, py.None())?;
        }
    }
    Ok(class)
}

/// A tuple of dicts, one per row, with these keys.
fn table<'py, const N: usize>(
    py: Python<'py>,
    keys: [&str; N],
    rows: Vec<[Bound<'py, PyAny>; N]>,
) -> PyResult<Bound<'py, PyTuple>> {
    let dicts = rows
        .into_iter()
        .map(|row| {
            let d = PyDict::new(py);
            keys.iter().zip(row).try_for_each(|(k, v)| d.set_item(k, v))?;
            Ok(d)
        })
        .collect::<PyResult<Vec<_>>>()?;
    PyTuple::new(py, dicts)
}

/// Adds `ERROR_CLASSES` (name, parent, builtin, doc), `ERROR_KINDS` (kind, class, doc) and
/// `ERROR_ATTRIBUTES` (name, type, doc).
fn register_tables(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let s = |x: &str| -> PyResult<Bound<'_, PyAny>> { Ok(x.into_pyobject(py)?.into_any()) };
    let classes = CLASSES
        .iter()
        .map(|c| Ok([s(c.name)?, c.parent.into_pyobject(py)?.into_any(), s(c.builtin)?, s(c.doc)?]))
        .collect::<PyResult<Vec<_>>>()?;
    m.add("ERROR_CLASSES", table(py, ["name", "parent", "builtin", "doc"], classes)?)?;
    let kinds = KINDS.iter().map(|(k, c, d)| Ok([s(k)?, s(c)?, s(d)?])).collect::<PyResult<Vec<_>>>()?;
    m.add("ERROR_KINDS", table(py, ["kind", "class", "doc"], kinds)?)?;
    let attributes =
        ATTRIBUTES.iter().map(|(n, t, _)| Ok([s(n)?, s(t)?, s(&attribute_doc(n))?])).collect::<PyResult<Vec<_>>>()?;
    m.add("ERROR_ATTRIBUTES", table(py, ["name", "type", "doc"], attributes)?)?;
    Ok(())
}

/// Creates the classes of [`CLASSES`] (each after its parent) and adds them and the tables to
/// the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    for spec in &CLASSES {
        let lock = cell(spec.name).ok_or_else(|| PyRuntimeError::new_err(format!("no cell for {}", spec.name)))?;
        let class = lock.get_or_try_init(py, || Ok::<_, PyErr>(make_class(py, spec)?.unbind()))?;
        m.add(spec.name, class.bind(py))?;
    }
    register_tables(m)
}

/// The value of one attribute.
pub(crate) enum Value {
    Str(String),
    Int(usize),
    Float(f64),
    Basis([usize; 3]),
    /// Where the error is: a tuple of keys (str) and indices (int).
    Location(crate::Location),
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
            Value::Location(at) => location_tuple(py, at)?.into_any(),
            Value::Object(o) => o.bind(py).clone(),
        })
    }
}

/// A location as Python sees it: a tuple of keys (str) and indices (int), `()` for the whole
/// input.
fn location_tuple<'py>(py: Python<'py>, at: &crate::Location) -> PyResult<Bound<'py, PyTuple>> {
    let steps = at
        .steps()
        .iter()
        .map(|step| match step {
            Step::Key(k) => Ok(k.into_pyobject(py)?.into_any()),
            Step::Index(i) => Ok(i.into_pyobject(py)?.into_any()),
        })
        .collect::<PyResult<Vec<_>>>()?;
    PyTuple::new(py, steps)
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

    /// Sets `argument`, and `location` to it (an attribute set later wins: this replaces a
    /// location copied from a cause).
    pub(crate) fn argument(self, argument: &str) -> Self {
        self.with("argument", Value::Str(argument.to_string()))
            .with("location", Value::Location(crate::Location::key(argument)))
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

/// The kind and attributes of an error.
type Described = (&'static str, Vec<(&'static str, Value)>);

/// The kind and attributes of a core error (every variant: a new one fails to compile here).
fn describe(err: &Error) -> Described {
    use Value::{Basis, Float, Int, Str};
    let s = |x: &str| Str(x.to_string());
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
        Error::Distortion { index, reason } => ("distortion", vec![("index", Int(*index)), ("reason", s(reason))]),
        Error::RzSingular { a_hat } => ("rz_singular", vec![("a_hat", Float(*a_hat))]),
    }
}

/// The kind and attributes of a vision error: its own variant, the core error's otherwise.
fn describe_vision(err: &VisionError) -> Described {
    let s = |x: &str| Value::Str(x.to_string());
    match err {
        VisionError::InvalidImage { what, reason } => {
            ("invalid_image", vec![("argument", s(what)), ("reason", s(reason))])
        }
        VisionError::Core(e) => describe(e),
    }
}

/// The kind and attributes of a calibration error: its own variants, the core error's otherwise.
fn describe_calibration(err: &CalibrationError) -> Described {
    use Value::{Int, Str};
    let s = |x: &str| Str(x.to_string());
    let opt = |x: &str| if x.is_empty() { None } else { Some(Str(x.to_string())) };
    match err {
        CalibrationError::File { file, field, reason } => {
            let field = opt(&field.to_string()).map(|f| ("field", f));
            ("calibration", [("file", s(file))].into_iter().chain(field).chain([("reason", s(reason))]).collect())
        }
        CalibrationError::InvalidPose { what, index, reason } => {
            ("invalid_pose", vec![("argument", s(what)), ("index", Int(*index)), ("reason", s(reason))])
        }
        CalibrationError::DegenerateMotion { poses, reason } => {
            ("degenerate_motion", vec![("count", Int(*poses)), ("reason", s(reason))])
        }
        CalibrationError::Core(e) => describe(e),
    }
}

/// The kind and attributes of a simulator error: its own variants, the lower error's otherwise.
fn describe_sim(err: &SimError) -> Described {
    use Value::{Float, Str};
    let s = |x: &str| Str(x.to_string());
    let opt = |x: &str| if x.is_empty() { None } else { Some(Str(x.to_string())) };
    match err {
        SimError::Scenario { key, reason } => {
            ("scenario", opt(&key.to_string()).map(|k| ("key", k)).into_iter().chain([("reason", s(reason))]).collect())
        }
        SimError::Urdf { file, message } => ("urdf", vec![("file", s(file)), ("reason", s(message))]),
        SimError::Unreachable { position_residual, .. } => {
            ("unreachable", vec![("argument", s("pose")), ("residual", Float(*position_residual))])
        }
        SimError::Core(e) => describe(e),
        SimError::Vision(e) => describe_vision(e),
        SimError::Calibration(e) => describe_calibration(e),
    }
}

/// The exception of an error of any layer: the class from [`Located::is_degenerate`], the
/// location from [`Located::location`], the kind and attributes `described` (each layer's
/// `describe_*`), the message the error's `Display` (with the scenario key among a core
/// error's remedies, [`Error::message_with_remedy`]).
fn py_error<E: Located>(err: &E, described: Described) -> PyError {
    let class = if err.is_degenerate() { Class::Degenerate } else { Class::InvalidInput };
    let (kind, mut attributes) = described;
    attributes.extend(err.location().map(|at| ("location", Value::Location(at))));
    // Python users pass depths to scenarios too: the remedy names the scenario key.
    let message = err.core().map_or_else(|| err.to_string(), |core| core.message_with_remedy(DEPTHS_REMEDY));
    PyError { class, message, kind: Some(kind), attributes }
}

impl From<&Error> for PyError {
    fn from(err: &Error) -> Self {
        py_error(err, describe(err))
    }
}

impl From<&VisionError> for PyError {
    fn from(err: &VisionError) -> Self {
        py_error(err, describe_vision(err))
    }
}

impl From<&CalibrationError> for PyError {
    fn from(err: &CalibrationError) -> Self {
        py_error(err, describe_calibration(err))
    }
}

impl From<&SimError> for PyError {
    fn from(err: &SimError) -> Self {
        py_error(err, describe_sim(err))
    }
}

/// `DegenerateGeometry` for scene geometry ([`Located::is_degenerate`]), `InvalidInput`
/// otherwise, with the error's fields as attributes: `?` on a `crate::Result` in a binding.
impl From<Error> for PyErr {
    fn from(err: Error) -> PyErr {
        PyError::from(&err).into()
    }
}

/// As a core error's: `?` on a vision `Result` in a binding.
impl From<VisionError> for PyErr {
    fn from(err: VisionError) -> PyErr {
        PyError::from(&err).into()
    }
}

/// As a core error's: `?` on a calibration `Result` in a binding.
impl From<CalibrationError> for PyErr {
    fn from(err: CalibrationError) -> PyErr {
        PyError::from(&err).into()
    }
}

/// As a core error's: `?` on a simulator's `Result` in a binding.
impl From<SimError> for PyErr {
    fn from(err: SimError) -> PyErr {
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
            for (name, _, _) in ATTRIBUTES {
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

/// [`reraise`] about item `index` of the sequence `argument`: `argument` set and `location`
/// `(argument, index)`.
pub(crate) fn reraise_item(cause: &PyErr, msg: String, argument: &str, index: usize) -> PyErr {
    let err = reraise(cause, msg, Some(argument));
    let location = Value::Location(crate::Location::key(argument).then_index(index));
    let set = Python::attach(|py| err.value(py).setattr("location", location.to_object(py)?));
    match set {
        Ok(()) => err,
        Err(e) => e,
    }
}
