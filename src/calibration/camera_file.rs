//! Camera calibration files: ROS `camera_info` YAML and OpenCV
//! `FileStorage` YAML or XML, read into [`Intrinsics`], [`Distortion`] and the image size.
//!
//! | format | recognised by | entries read |
//! |---|---|---|
//! | ROS camera_info YAML | a `distortion_model` entry | `image_width`, `image_height`, `camera_matrix: {rows, cols, data}`, `distortion_model` (`plumb_bob`, `rational_polynomial`, or `equidistant` with 4 coefficients `k1, k2, k3, k4`), `distortion_coefficients: {rows, cols, data}` |
//! | OpenCV FileStorage YAML | otherwise | `image_width`, `image_height`, `camera_matrix: !!opencv-matrix {rows, cols, dt, data}`, `distortion_coefficients` (or `dist_coeffs`), the model from an optional `distortion_model` entry (as ROS names it; XML) or else from the number of coefficients (4, 5 or 8: 4 is `plumb_bob`, as `cv2.calibrateCamera` writes; a `cv2.fisheye` calibration needs `distortion_model: equidistant`) |
//! | OpenCV FileStorage XML | a first character `<` | the same entries under `<opencv_storage>`, matrices as `<rows>`, `<cols>`, `<data>` |
//!
//! OpenCV 4 writes the directive `%YAML:1.0`, which is not YAML (the directive is
//! `%YAML 1.0`) and which YAML parsers refuse: that line is blanked before parsing (OpenCV 5
//! writes `%YAML 1.2`, accepted as it is). The `!!opencv-matrix` tag is ignored.
//!
//! The camera matrix must be `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`: OpenCV's and ROS's
//! models have no skew, so a file with `K[0,1] != 0` is refused rather than read differently
//! from the tools that wrote it. Every error is a [`CalibrationError::File`] naming the file and
//! the entry at fault and never the file's contents: a text where a number was expected is
//! described by its length only (a scenario can point at any file, and its strings may be
//! secrets); only a distortion model name that looks like one (lower-case letters, digits and `_`, at
//! most 32) is quoted.
//!
//! `image_width` and `image_height` are optional (OpenCV's stereo and hand-written
//! calibrations omit them): without them the image size is unknown (`None`).
//!
//! **Values that describe a lens.** `fx` and `fy` must be in (0, 1e6] pixels, `cx` and `cy`
//! within +-1e6 pixels (the scenario files' bounds), and every distortion coefficient within
//! +-[`MAX_DISTORTION_COEFFICIENT`]: real lenses have coefficients of order 1 (the strongest
//! rational models a few hundred), and larger values (`k1 = 1e300`) overflow the model.
//!
//! **Hostile files.** A file is read only if it is a regular file of at most
//! [`MAX_CALIBRATION_BYTES`] (module [`input_file`](crate::input_file)). YAML aliases
//! (`*name`) are refused: the parser expands each alias into a copy of its anchor, so nine
//! levels of nine aliases (a 1 KB file, the "billion laughs") would build 9^9 nodes, and no
//! real calibration file uses them (OpenCV and ROS never write anchors). Refusing them, found
//! in one pass over the parser's events before anything is built, bounds the work by the
//! file's size; bounding the expanded node count instead would accept files that no tool
//! writes. XML is parsed without DTDs (roxmltree's default: no entity expansion) and with at
//! most [`MAX_XML_NODES`] nodes. A key or element given twice is refused in both formats.

use std::path::Path;

use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::Marker;
use yaml_rust2::{Yaml, YamlLoader};

use crate::calibration::error::{CalibrationError, Result};
use crate::core::camera::Intrinsics;
use crate::core::distortion::{Distortion, DistortionModel};
use crate::error::Error;
pub use crate::input_file::MAX_CALIBRATION_BYTES;
use crate::input_file::read_text;

/// The largest absolute value of a distortion coefficient (module docs).
pub const MAX_DISTORTION_COEFFICIENT: f64 = 1e4;
/// The largest focal length and principal-point coordinate, pixels.
pub const MAX_INTRINSIC_PIXELS: f64 = 1e6;
/// The most nodes (elements, text, attributes) an XML calibration file may have.
pub const MAX_XML_NODES: u32 = 100_000;

/// A camera calibration: intrinsics, lens distortion and the image size it was made for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// The camera matrix (without skew).
    pub intrinsics: Intrinsics,
    /// The distortion model and coefficients.
    pub distortion: Distortion,
    /// `(width, height)` in pixels; `None` when the file does not give it (OpenCV files may
    /// omit `image_width` and `image_height`).
    pub image_size: Option<(u32, u32)>,
}

/// Reads a calibration file of any of the three formats (module docs): a regular file of at
/// most [`MAX_CALIBRATION_BYTES`], UTF-8.
pub fn load_calibration(path: impl AsRef<Path>) -> Result<Calibration> {
    let path = path.as_ref();
    let file = path.display().to_string();
    let text = read_text(path, MAX_CALIBRATION_BYTES).map_err(|reason| err(&file, "", reason))?;
    parse_calibration(&text, &file)
}

/// Reads calibration text; `file` names it in errors.
pub fn parse_calibration(text: &str, file: &str) -> Result<Calibration> {
    let raw = if text.trim_start().starts_with('<') { from_xml(text, file)? } else { from_yaml(text, file)? };
    raw.validate(file)
}

/// A matrix entry as read: its rows, columns and values.
struct RawMatrix {
    rows: i64,
    cols: i64,
    data: Vec<f64>,
}

/// The entries common to the formats, before validation.
struct Raw {
    width: Option<i64>,
    height: Option<i64>,
    camera_matrix: RawMatrix,
    /// The name of the distortion entry that was found.
    dist_key: &'static str,
    distortion: RawMatrix,
    model: Option<String>,
}

fn err(file: &str, field: impl Into<String>, reason: impl Into<String>) -> CalibrationError {
    CalibrationError::File {
        file: file.to_string(),
        field: crate::Location::parse(&field.into()),
        reason: reason.into(),
    }
}

impl Raw {
    fn validate(self, file: &str) -> Result<Calibration> {
        let size = |key: &str, v: i64| {
            u32::try_from(v)
                .ok()
                .filter(|&v| v > 0)
                .ok_or_else(|| err(file, key, format!("expected a positive integer, got {v}")))
        };
        let image_size = match (self.width, self.height) {
            (Some(w), Some(h)) => Some((size("image_width", w)?, size("image_height", h)?)),
            (None, None) => None,
            (None, Some(_)) => {
                return Err(err(file, "image_width", "missing (image_height is given: give both or neither)"));
            }
            (Some(_), None) => {
                return Err(err(file, "image_height", "missing (image_width is given: give both or neither)"));
            }
        };

        let km = &self.camera_matrix;
        if km.rows != 3 || km.cols != 3 {
            return Err(err(file, "camera_matrix", format!("expected a 3x3 matrix, got {}x{}", km.rows, km.cols)));
        }
        check_count(file, "camera_matrix", km)?;
        if let Some(i) = km.data.iter().position(|v| !v.is_finite()) {
            return Err(err(file, format!("camera_matrix.data[{i}]"), format!("non-finite value {}", km.data[i])));
        }
        check_lens_intrinsics(file, &km.data)?;
        let k = nalgebra::Matrix3::from_row_slice(&km.data);
        if k[(0, 1)] != 0.0 {
            return Err(err(
                file,
                "camera_matrix",
                format!(
                    "K[0,1] = {} but calibration files describe a camera without skew ([[fx, 0, cx], [0, fy, cy], [0, 0, 1]])",
                    crate::error::Short(k[(0, 1)])
                ),
            ));
        }
        let intrinsics = Intrinsics::from_matrix(&k).map_err(|e| err(file, "camera_matrix", e.to_string()))?;

        let key = self.dist_key;
        let dm = &self.distortion;
        check_count(file, key, dm)?;
        if dm.rows != 1 && dm.cols != 1 {
            return Err(err(file, key, format!("expected a row or column vector, got {}x{}", dm.rows, dm.cols)));
        }
        check_coefficients(file, key, &dm.data)?;
        let distortion = match &self.model {
            Some(name) => {
                let model = DistortionModel::from_name(name).ok_or_else(|| {
                    err(
                        file,
                        "distortion_model",
                        format!("unknown distortion model {}; expected {}", model_name(name), DistortionModel::NAMES),
                    )
                })?;
                Distortion::with_model(model, &dm.data)
            }
            None => Distortion::from_coefficients(&dm.data),
        }
        .map_err(|e| {
            let reason = match e {
                Error::InvalidParameter { reason, .. } => reason,
                other => other.to_string(),
            };
            err(file, key, format!("wrong coefficient count: {reason}"))
        })?;
        Ok(Calibration { intrinsics, distortion, image_size })
    }
}

/// Distortion coefficients: finite and within +-[`MAX_DISTORTION_COEFFICIENT`].
fn check_coefficients(file: &str, key: &str, data: &[f64]) -> Result<()> {
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(err(file, format!("{key}.data[{i}]"), format!("non-finite value {}", data[i])));
    }
    if let Some(i) = data.iter().position(|v| v.abs() > MAX_DISTORTION_COEFFICIENT) {
        let reason = format!(
            "{:e} does not describe a lens: distortion coefficients are within +-{MAX_DISTORTION_COEFFICIENT:e}",
            data[i]
        );
        return Err(err(file, format!("{key}.data[{i}]"), reason));
    }
    Ok(())
}

/// fx, fy at most [`MAX_INTRINSIC_PIXELS`] and cx, cy within +-[`MAX_INTRINSIC_PIXELS`]
/// (row-major K: fx at 0, cx at 2, fy at 4, cy at 5); fx, fy > 0 is checked by
/// [`Intrinsics::from_matrix`].
fn check_lens_intrinsics(file: &str, k: &[f64]) -> Result<()> {
    for (i, name) in [(0, "fx"), (4, "fy")] {
        if k[i] > MAX_INTRINSIC_PIXELS {
            let reason =
                format!("{name} = {:e} does not describe a lens: expected at most {MAX_INTRINSIC_PIXELS:e} px", k[i]);
            return Err(err(file, format!("camera_matrix.data[{i}]"), reason));
        }
    }
    for (i, name) in [(2, "cx"), (5, "cy")] {
        if k[i].abs() > MAX_INTRINSIC_PIXELS {
            let reason =
                format!("{name} = {:e} does not describe a lens: expected within +-{MAX_INTRINSIC_PIXELS:e} px", k[i]);
            return Err(err(file, format!("camera_matrix.data[{i}]"), reason));
        }
    }
    Ok(())
}

fn check_count(file: &str, key: &str, m: &RawMatrix) -> Result<()> {
    // checked: rows x cols of i64::MAX overflows.
    if m.rows < 0
        || m.cols < 0
        || m.rows.checked_mul(m.cols).and_then(|c| usize::try_from(c).ok()) != Some(m.data.len())
    {
        return Err(err(
            file,
            format!("{key}.data"),
            format!("rows x cols = {} x {} but data has {} values", m.rows, m.cols, m.data.len()),
        ));
    }
    Ok(())
}

/// Blanks OpenCV 4's `%YAML:1.0` directive line (keeping the line numbers).
fn strip_opencv_directive(text: &str) -> std::borrow::Cow<'_, str> {
    let start = text.len() - text.trim_start_matches('\u{feff}').len();
    let body = &text[start..];
    if body.starts_with("%YAML:") {
        let end = body.find('\n').unwrap_or(body.len());
        std::borrow::Cow::Owned(format!("#{}", &body[1..end]) + &body[end..])
    } else {
        std::borrow::Cow::Borrowed(body)
    }
}

/// A text from the file, by its length only (module docs).
fn text_of_length(s: &str) -> String {
    format!("a text of {} characters", s.chars().count())
}

/// A name quoted if it looks like one (module docs), else by its length.
fn model_name(s: &str) -> String {
    let plausible =
        !s.is_empty() && s.len() <= 32 && s.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
    if plausible { format!("\"{s}\"") } else { text_of_length(s) }
}

fn yaml_kind(v: &Yaml) -> String {
    match v {
        Yaml::Real(s) => format!("{s:?}"),
        Yaml::Integer(i) => i.to_string(),
        Yaml::String(s) => text_of_length(s),
        Yaml::Boolean(b) => format!("the boolean {b}"),
        Yaml::Array(_) => "a list".into(),
        Yaml::Hash(_) => "a mapping".into(),
        Yaml::Null => "null".into(),
        _ => "an unreadable value".into(),
    }
}

/// Finds the first YAML alias (module docs: aliases are refused, so the loader, which would
/// expand them, runs only on files without any).
#[derive(Default)]
struct AliasFinder {
    alias_at: Option<Marker>,
}

impl MarkedEventReceiver for AliasFinder {
    fn on_event(&mut self, ev: Event, mark: Marker) {
        if self.alias_at.is_none() && matches!(ev, Event::Alias(_)) {
            self.alias_at = Some(mark);
        }
    }
}

/// The YAML documents of `text`, refusing aliases: one pass over the parser's events (linear
/// in the text), then the loader.
fn load_yaml(text: &str, file: &str) -> Result<Vec<Yaml>> {
    let not_yaml = |e: yaml_rust2::ScanError| err(file, "", format!("not valid YAML: {e}"));
    let mut finder = AliasFinder::default();
    Parser::new_from_str(text).load(&mut finder, true).map_err(not_yaml)?;
    if let Some(m) = finder.alias_at {
        let reason = format!(
            "YAML alias at line {}, column {}: aliases are refused (calibration files never need them, and nested ones expand exponentially)",
            m.line(),
            m.col() + 1
        );
        return Err(err(file, "", reason));
    }
    YamlLoader::load_from_str(text).map_err(not_yaml)
}

fn from_yaml(text: &str, file: &str) -> Result<Raw> {
    let docs = load_yaml(&strip_opencv_directive(text), file)?;
    let Some(doc) = docs.first() else {
        return Err(err(file, "", "empty document"));
    };
    if doc.as_hash().is_none() {
        return Err(err(file, "", format!("expected a mapping at the top level, got {}", yaml_kind(doc))));
    }
    let get = |key: &str| -> Result<&Yaml> {
        match &doc[key] {
            Yaml::BadValue => Err(err(file, key, "missing")),
            v => Ok(v),
        }
    };
    let int = |field: &str, v: &Yaml| -> Result<i64> {
        v.as_i64().ok_or_else(|| err(file, field, format!("expected an integer, got {}", yaml_kind(v))))
    };
    let matrix = |key: &str| -> Result<RawMatrix> {
        let m = get(key)?;
        if m.as_hash().is_none() {
            return Err(err(file, key, format!("expected a matrix {{rows, cols, data}}, got {}", yaml_kind(m))));
        }
        let sub = |name: &str| match &m[name] {
            Yaml::BadValue => Err(err(file, format!("{key}.{name}"), "missing")),
            v => Ok(v),
        };
        let rows = int(&format!("{key}.rows"), sub("rows")?)?;
        let cols = int(&format!("{key}.cols"), sub("cols")?)?;
        let data = sub("data")?;
        let Some(items) = data.as_vec() else {
            return Err(err(
                file,
                format!("{key}.data"),
                format!("expected a list of numbers, got {}", yaml_kind(data)),
            ));
        };
        let data = items
            .iter()
            .enumerate()
            .map(|(i, v)| match v {
                Yaml::Integer(n) => Ok(*n as f64),
                Yaml::Real(_) => v.as_f64().ok_or_else(|| err(file, format!("{key}.data[{i}]"), "not a number")),
                other => Err(err(file, format!("{key}.data[{i}]"), format!("non-numeric value {}", yaml_kind(other)))),
            })
            .collect::<Result<Vec<f64>>>()?;
        Ok(RawMatrix { rows, cols, data })
    };
    let optional_int = |key: &str| match &doc[key] {
        Yaml::BadValue => Ok(None),
        v => int(key, v).map(Some),
    };
    let width = optional_int("image_width")?;
    let height = optional_int("image_height")?;
    let camera_matrix = matrix("camera_matrix")?;
    let model = match &doc["distortion_model"] {
        Yaml::BadValue => None,
        Yaml::String(s) => Some(s.clone()),
        other => return Err(err(file, "distortion_model", format!("expected a name, got {}", yaml_kind(other)))),
    };
    let dist_key = if model.is_none()
        && matches!(doc["distortion_coefficients"], Yaml::BadValue)
        && !matches!(doc["dist_coeffs"], Yaml::BadValue)
    {
        "dist_coeffs"
    } else {
        "distortion_coefficients"
    };
    let distortion = matrix(dist_key)?;
    Ok(Raw { width, height, camera_matrix, dist_key, distortion, model })
}

type XmlNode<'a, 'input> = roxmltree::Node<'a, 'input>;

fn xml_child<'a, 'input>(
    file: &str,
    node: XmlNode<'a, 'input>,
    name: &str,
    field: &str,
) -> Result<XmlNode<'a, 'input>> {
    let mut found = node.children().filter(|c| c.is_element() && c.tag_name().name() == name);
    let first = found.next().ok_or_else(|| err(file, field, "missing"))?;
    if let Some(second) = found.next() {
        let pos = second.document().text_pos_at(second.range().start);
        return Err(err(file, field, format!("given twice (again at line {}): give it once", pos.row)));
    }
    Ok(first)
}

fn xml_has(node: XmlNode<'_, '_>, name: &str) -> bool {
    node.children().any(|c| c.is_element() && c.tag_name().name() == name)
}

fn xml_text<'a>(node: XmlNode<'a, '_>) -> &'a str {
    node.text().unwrap_or("").trim()
}

/// The integer in the element `name` of `node`, `field` naming it in errors.
fn xml_int(file: &str, node: XmlNode<'_, '_>, name: &str, field: &str) -> Result<i64> {
    let t = xml_text(xml_child(file, node, name, field)?);
    t.parse::<i64>().map_err(|_| err(file, field, format!("expected an integer, got {}", text_of_length(t))))
}

fn xml_matrix(file: &str, root: XmlNode<'_, '_>, key: &str) -> Result<RawMatrix> {
    let m = xml_child(file, root, key, key)?;
    let rows = xml_int(file, m, "rows", &format!("{key}.rows"))?;
    let cols = xml_int(file, m, "cols", &format!("{key}.cols"))?;
    let data = xml_child(file, m, "data", &format!("{key}.data"))?
        .text()
        .unwrap_or("")
        .split_whitespace()
        .enumerate()
        .map(|(i, s)| {
            parse_opencv_float(s).ok_or_else(|| {
                err(file, format!("{key}.data[{i}]"), format!("non-numeric value: {}", text_of_length(s)))
            })
        })
        .collect::<Result<Vec<f64>>>()?;
    Ok(RawMatrix { rows, cols, data })
}

fn from_xml(text: &str, file: &str) -> Result<Raw> {
    // No DTD (so no entity expansion) and a bounded node count (module docs).
    let options = roxmltree::ParsingOptions { allow_dtd: false, nodes_limit: MAX_XML_NODES, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(text, options)
        .map_err(|e| err(file, "", format!("not valid XML: {e}")))?;
    let root = doc.root_element();
    if root.tag_name().name() != "opencv_storage" {
        return Err(err(
            file,
            "",
            format!("expected the root element <opencv_storage>, got {}", model_name(root.tag_name().name())),
        ));
    }
    let optional_int = |name: &str| match xml_has(root, name) {
        true => xml_int(file, root, name, name).map(Some),
        false => Ok(None),
    };
    let width = optional_int("image_width")?;
    let height = optional_int("image_height")?;
    let camera_matrix = xml_matrix(file, root, "camera_matrix")?;
    let model = if xml_has(root, "distortion_model") {
        Some(xml_text(xml_child(file, root, "distortion_model", "distortion_model")?).to_string())
    } else {
        None
    };
    let dist_key = if !xml_has(root, "distortion_coefficients") && xml_has(root, "dist_coeffs") {
        "dist_coeffs"
    } else {
        "distortion_coefficients"
    };
    let distortion = xml_matrix(file, root, dist_key)?;
    Ok(Raw { width, height, camera_matrix, dist_key, distortion, model })
}

/// A float as OpenCV writes it: Rust's syntax (which accepts `1.` and `-0.`), plus `.Nan`
/// and `.Inf` (returned as non-finite values, refused later with the field named).
fn parse_opencv_float(s: &str) -> Option<f64> {
    match s {
        ".Nan" | ".nan" | ".NaN" => Some(f64::NAN),
        ".Inf" | ".inf" | "+.Inf" => Some(f64::INFINITY),
        "-.Inf" | "-.inf" => Some(f64::NEG_INFINITY),
        _ => s.parse().ok(),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    const ROS: &str = "image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [800.5, 0, 320.25, 0, 801.5, 240.75, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.3, 0.1, 0.001, -0.002, 0]
";

    const OPENCV4: &str = "%YAML:1.0
---
image_width: 640
image_height: 480
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 800., 0., 320., 0., 810.5, 240., 0., 0., 1. ]
dist_coeffs: !!opencv-matrix
   rows: 1
   cols: 8
   dt: d
   data: [ -0.29999999999999999, 0.1, 0.001, -0.002, 0., 0.1, 0.0, 0.0 ]
";

    const XML: &str = r#"<?xml version="1.0"?>
<opencv_storage>
<image_width>640</image_width>
<image_height>480</image_height>
<camera_matrix type_id="opencv-matrix">
  <rows>3</rows>
  <cols>3</cols>
  <dt>d</dt>
  <data>
    800. 0. 320. 0. 810.5 240. 0. 0. 1.</data></camera_matrix>
<distortion_coefficients type_id="opencv-matrix">
  <rows>1</rows>
  <cols>4</cols>
  <dt>d</dt>
  <data>
    -0.3 0.1 0.001 -0.002</data></distortion_coefficients>
</opencv_storage>
"#;

    fn field_of(e: CalibrationError) -> (String, String) {
        match e {
            CalibrationError::File { field, reason, .. } => (field.to_string(), reason),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn reads_the_three_formats() {
        let c = parse_calibration(ROS, "ros.yaml").unwrap();
        assert_eq!(c.image_size, Some((640, 480)));
        assert_eq!(c.intrinsics.fku(), 800.5);
        assert_eq!(c.intrinsics.v0(), 240.75);
        assert_eq!(c.distortion.model(), DistortionModel::PlumbBob);
        assert_eq!(c.distortion.coefficients(), &[-0.3, 0.1, 0.001, -0.002, 0.0]);

        let c = parse_calibration(OPENCV4, "cv.yaml").unwrap();
        assert_eq!(c.intrinsics.fkv(), 810.5);
        assert_eq!(c.distortion.model(), DistortionModel::RationalPolynomial);
        assert_eq!(c.distortion.coefficients()[5], 0.1);

        let c = parse_calibration(XML, "cv.xml").unwrap();
        assert_eq!(c.image_size, Some((640, 480)));
        assert_eq!(c.intrinsics.u0(), 320.0);
        assert_eq!(c.distortion.coefficients(), &[-0.3, 0.1, 0.001, -0.002, 0.0]);
    }

    #[test]
    fn reads_fisheye_lenses() {
        let ros = ROS.replace("plumb_bob", "equidistant").replace("cols: 5", "cols: 4").replace("0.002, 0]", "0.002]");
        let c = parse_calibration(&ros, "fisheye.yaml").unwrap();
        assert_eq!(c.distortion.model(), DistortionModel::Equidistant);
        assert_eq!(c.distortion.coefficients(), &[-0.3, 0.1, 0.001, -0.002]);
        let xml = XML.replace("<image_width>", "<distortion_model>equidistant</distortion_model>\n<image_width>");
        let c = parse_calibration(&xml, "fisheye.xml").unwrap();
        assert_eq!(c.distortion.model(), DistortionModel::Equidistant);
        // Without the model's name, 4 coefficients are plumb_bob (cv2.calibrateCamera's).
        assert_eq!(parse_calibration(XML, "cv.xml").unwrap().distortion.model(), DistortionModel::PlumbBob);
        // equidistant takes 4 coefficients: 5 are refused, naming the entry.
        let (f, r) = field_of(parse_calibration(&ROS.replace("plumb_bob", "equidistant"), "bad.yaml").unwrap_err());
        assert_eq!(f, "distortion_coefficients");
        assert!(r.contains("equidistant") && r.contains("got 5"), "{r}");
        let (f, _) = field_of(parse_calibration(&ros.replace("-0.3,", ".nan,"), "bad.yaml").unwrap_err());
        assert_eq!(f, "distortion_coefficients.data[0]");
    }

    #[test]
    fn malformed_files_name_the_field() {
        let cases: [(String, &str, &str); 9] = [
            (ROS.replace("image_width: 640\n", ""), "image_width", "missing (image_height is given"),
            (ROS.replace("image_height: 480", "image_height: tall"), "image_height", "integer"),
            (ROS.replace("cols: 3", "cols: 2"), "camera_matrix", "3x3"),
            (ROS.replace("800.5, 0, 320.25", "800.5, 0, abc"), "camera_matrix.data[2]", "non-numeric"),
            (ROS.replace("800.5, 0, 320.25", "800.5, 3, 320.25"), "camera_matrix", "skew"),
            (ROS.replace("plumb_bob", "fisheye"), "distortion_model", "unknown"),
            (
                ROS.replace("cols: 5", "cols: 6").replace("0.002, 0]", "0.002, 0, 0]"),
                "distortion_coefficients",
                "count",
            ),
            (ROS.replace("0.002, 0]", "0.002]"), "distortion_coefficients.data", "data has 4"),
            (ROS.replace("0, 0, 1]", "0, 0, 2]"), "camera_matrix", "last row"),
        ];
        for (text, field, reason) in cases {
            let (f, r) = field_of(parse_calibration(&text, "bad.yaml").unwrap_err());
            assert_eq!(f, field, "{r}");
            assert!(r.contains(reason), "{field}: {r}");
        }
        let (f, _) = field_of(parse_calibration(&XML.replace("<rows>3</rows>", ""), "bad.xml").unwrap_err());
        assert_eq!(f, "camera_matrix.rows");
        let (f, _) = field_of(parse_calibration(&XML.replace("810.5", "x"), "bad.xml").unwrap_err());
        assert_eq!(f, "camera_matrix.data[4]");
        let (f, _) = field_of(parse_calibration("<foo/>", "bad.xml").unwrap_err());
        assert_eq!(f, "");
        let e = load_calibration("/nonexistent/cal.yaml").unwrap_err();
        assert!(e.to_string().contains("/nonexistent/cal.yaml"), "{e}");
        // A huge skew term is written short, not with its 301 digits.
        let (_, r) = field_of(
            parse_calibration(&ROS.replace("800.5, 0, 320.25", "800.5, 1e300, 320.25"), "x.yaml").unwrap_err(),
        );
        assert!(r.contains("K[0,1] = 1.0e300 but"), "{r}");
    }

    /// Regression (issue 16): nine levels of nine aliases (about 600 bytes) made the loader
    /// build 9^9 nodes and abort the process; aliases are now refused before loading.
    #[test]
    fn alias_bombs_are_refused_quickly() {
        let mut bomb = String::from("a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]\n");
        for i in 1..10 {
            bomb += &format!("a{i}: &a{i} [{}]\n", vec![format!("*a{}", i - 1); 9].join(", "));
        }
        let in_matrix = ROS.replace("data: [800.5", "data: &k [800.5").replace("cols: 5", "cols: 5\n  extra: *k");
        for text in [bomb.clone() + ROS, in_matrix] {
            let t = std::time::Instant::now();
            let (field, reason) = field_of(parse_calibration(&text, "bomb.yaml").unwrap_err());
            assert_eq!(field, "");
            assert!(reason.contains("alias"), "{reason}");
            assert!(t.elapsed().as_secs() < 5, "hang test: {:?}", t.elapsed());
        }
        // An anchor without alias is harmless and read as usual.
        assert!(parse_calibration(&ROS.replace("data: [800.5", "data: &k [800.5"), "a.yaml").is_ok());
    }

    /// Regression (issue 16): duplicate XML elements were accepted (the first one read) while
    /// duplicate YAML keys were refused; both are refused now.
    #[test]
    fn duplicates_are_refused_in_both_formats() {
        let twice = XML.replace(
            "<image_height>480</image_height>",
            "<image_height>480</image_height>\n<image_height>48</image_height>",
        );
        let (field, reason) = field_of(parse_calibration(&twice, "d.xml").unwrap_err());
        assert_eq!(field, "image_height");
        assert!(reason.contains("twice"), "{reason}");
        let rows_twice = XML.replace("<rows>3</rows>", "<rows>3</rows><rows>3</rows>");
        assert_eq!(field_of(parse_calibration(&rows_twice, "d.xml").unwrap_err()).0, "camera_matrix.rows");
        let yaml_twice = ROS.replace("image_height: 480\n", "image_height: 480\nimage_height: 48\n");
        assert!(parse_calibration(&yaml_twice, "d.yaml").is_err());
    }

    /// Regression (issue 16): OpenCV files without image_width / image_height were refused;
    /// the size is optional and read as unknown.
    #[test]
    fn image_size_is_optional() {
        let no_size = OPENCV4.replace("image_width: 640\nimage_height: 480\n", "");
        let c = parse_calibration(&no_size, "cv.yaml").unwrap();
        assert_eq!(c.image_size, None);
        assert_eq!(c.intrinsics.fkv(), 810.5);
        let xml = XML.replace("<image_width>640</image_width>\n<image_height>480</image_height>\n", "");
        assert_eq!(parse_calibration(&xml, "cv.xml").unwrap().image_size, None);
        let (field, _) =
            field_of(parse_calibration(&XML.replace("<image_width>640</image_width>", ""), "cv.xml").unwrap_err());
        assert_eq!(field, "image_width");
    }

    /// Regression (issue 16): k1 = 1e300 loaded; coefficients and intrinsics must describe a
    /// lens (module docs), checked at the bounds.
    #[test]
    fn values_that_do_not_describe_a_lens_are_refused() {
        let k1 = |v: &str| ROS.replace("data: [-0.3, 0.1", &format!("data: [{v}, 0.1"));
        let (field, reason) = field_of(parse_calibration(&k1("1e300"), "k.yaml").unwrap_err());
        assert_eq!(field, "distortion_coefficients.data[0]");
        assert!(reason.contains("lens"), "{reason}");
        assert!(parse_calibration(&k1("-1e4"), "k.yaml").is_ok());
        assert!(parse_calibration(&k1("-10000.001"), "k.yaml").is_err());
        let fx = |v: &str| ROS.replace("data: [800.5,", &format!("data: [{v},"));
        assert_eq!(field_of(parse_calibration(&fx("1e7"), "k.yaml").unwrap_err()).0, "camera_matrix.data[0]");
        assert!(parse_calibration(&fx("1e6"), "k.yaml").is_ok());
        assert_eq!(field_of(parse_calibration(&fx("0"), "k.yaml").unwrap_err()).0, "camera_matrix");
        let cy = ROS.replace("240.75", "-2e6");
        assert_eq!(field_of(parse_calibration(&cy, "k.yaml").unwrap_err()).0, "camera_matrix.data[5]");
    }

    /// Regression (issue 16): a text value was quoted in full ("got the string \"AKIA-...\"").
    #[test]
    fn errors_do_not_quote_the_file() {
        let marker = "SECRET-MARKER-0123";
        let cases = [
            ROS.replace("image_width: 640", &format!("image_width: {marker}")),
            format!("{marker}\n"),
            ROS.replace("plumb_bob", marker),
            ROS.replace("800.5, 0, 320.25", &format!("800.5, 0, {marker}")),
            XML.replace("810.5", marker),
            XML.replace("<rows>3</rows>", &format!("<rows>{marker}</rows>")),
            XML.replace("opencv_storage", marker),
        ];
        for text in cases {
            let message = parse_calibration(&text, "s.yaml").unwrap_err().to_string();
            assert!(!message.contains("SECRET"), "{message}");
        }
    }
}
