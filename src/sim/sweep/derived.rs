//! The derived keys of a sweep, computed from the scenario (its value tree) rather than set
//! verbatim: a lens change (`lens_ratio`), K_hat's errors (`focal_error`,
//! `principal_point_error`) and an extra roll of the start about the optical axis
//! (`roll_deg`). docs/guides/sweeps.md and `vsinv.sweep` describe them.

use nalgebra::{Matrix4, Vector3};
use serde_json::{Map, Value, json};

use crate::core::se3;
use crate::sim::error::{Result, SimError};

/// Keys computed from the scenario rather than set verbatim, in the order they are applied.
pub const DERIVED_KEYS: [&str; 4] = ["lens_ratio", "focal_error", "principal_point_error", "roll_deg"];

/// A sweep's error about `key`: `vary key 'key': reason`.
pub(crate) fn key_error(key: &str, reason: impl std::fmt::Display) -> SimError {
    SimError::Scenario { key: crate::Location::root(), reason: format!("vary key '{key}': {reason}") }
}

/// A derived key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Derived {
    /// `lens_ratio` r: the servo camera's focal terms are the reference camera's times r.
    LensRatio,
    /// `focal_error` e: K_hat's focal terms are the servo camera's at t = 0 times (1 + e).
    FocalError,
    /// `principal_point_error` d: d pixels added to K_hat's u0 and v0.
    PrincipalPointError,
    /// `roll_deg` a: the start rotation R becomes R Rz(a).
    Roll,
}

/// The fields of an estimate (K_hat) section.
const ESTIMATE_FIELDS: [&str; 5] = ["fku", "fkv", "u0", "v0", "skew_deg"];

impl Derived {
    /// The key of that name.
    pub fn named(key: &str) -> Option<Self> {
        let all = [Self::LensRatio, Self::FocalError, Self::PrincipalPointError, Self::Roll];
        DERIVED_KEYS.iter().position(|k| *k == key).map(|i| all[i])
    }

    /// The key's name (one of [`DERIVED_KEYS`], in the order they are applied).
    pub fn name(self) -> &'static str {
        DERIVED_KEYS[self.order()]
    }

    /// Where the key comes in the order of application.
    pub fn order(self) -> usize {
        match self {
            Self::LensRatio => 0,
            Self::FocalError => 1,
            Self::PrincipalPointError => 2,
            Self::Roll => 3,
        }
    }

    /// Applies the key with `value` (a finite number) to the scenario `d`.
    pub fn apply(self, d: &mut Map<String, Value>, value: &Value) -> Result<()> {
        let v = match value {
            Value::Number(n) => n.as_f64().filter(|x| x.is_finite()),
            _ => None,
        };
        let Some(v) = v else { return Err(key_error(self.name(), format!("expected a finite number, got {value}"))) };
        match self {
            Self::LensRatio => lens_ratio(d, v),
            Self::FocalError => focal_error(d, v),
            Self::PrincipalPointError => principal_point_error(d, v),
            Self::Roll => roll(d, v),
        }
    }
}

fn number(table: &Map<String, Value>, field: &str, key: &str) -> Result<f64> {
    table.get(field).and_then(Value::as_f64).ok_or_else(|| key_error(key, format!("{field}: expected a number")))
}

/// A camera table with its intrinsics as numbers: the derived keys scale them, which a
/// calibration file does not allow.
fn numbers_of(table: &Value, key: &str) -> Result<Map<String, Value>> {
    match table.as_object() {
        Some(t) if t.contains_key("fku") && t.contains_key("fkv") => Ok(t.clone()),
        _ => Err(key_error(
            key,
            "the lens and K_hat keys (lens_ratio, focal_error, principal_point_error) need fku, fkv, u0 and v0 as \
             numbers, not calibration = \"file\"",
        )),
    }
}

/// `np.interp(x, xp, fp)` (the value at a knot is the knot's).
fn interp(x: f64, xp: &[f64], fp: &[f64]) -> f64 {
    let n = xp.len();
    if x <= xp[0] || n == 1 {
        return if x >= xp[n - 1] && n > 1 { fp[n - 1] } else { fp[0] };
    }
    if x >= xp[n - 1] {
        return fp[n - 1];
    }
    let j = xp.iter().rposition(|&k| k <= x).unwrap_or(0);
    if xp[j] == x {
        return fp[j];
    }
    let slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]);
    slope * (x - xp[j]) + fp[j]
}

fn floats(v: Option<&Value>) -> Option<Vec<f64>> {
    let list = v?.as_array()?;
    (!list.is_empty()).then(|| list.iter().filter_map(Value::as_f64).collect())
}

/// The servo camera at t = 0 (a zoom schedule interpolated at t = 0) as an estimate table.
fn camera_at_start(d: &Map<String, Value>, key: &str) -> Result<Map<String, Value>> {
    let has_camera = d.get("camera").and_then(Value::as_object).is_some_and(|c| !c.is_empty());
    let which = if has_camera { "camera" } else { "reference_camera" };
    let mut cam = numbers_of(d.get(which).unwrap_or(&Value::Null), which)?;
    if let Some(zoom) = cam.get("zoom").and_then(Value::as_object).cloned()
        && let Some(times) = floats(zoom.get("times"))
    {
        for f in ["fku", "fkv", "u0", "v0"] {
            if let Some(values) = floats(zoom.get(f)) {
                if values.len() != times.len() {
                    return Err(key_error(key, format!("{which}.zoom.{f}: not as many values as times")));
                }
                cam.insert(f.into(), json!(interp(0.0, &times, &values)));
            }
        }
    }
    let mut out: Map<String, Value> =
        ESTIMATE_FIELDS.iter().filter_map(|f| cam.get(*f).map(|v| ((*f).to_string(), v.clone()))).collect();
    out.entry("skew_deg").or_insert(json!(90.0));
    Ok(out)
}

/// Fills a missing (or null) `camera` / `estimate` section with its default (the reference
/// camera; the servo camera at t = 0); any other missing section becomes an empty table.
pub(crate) fn ensure_section(d: &mut Map<String, Value>, name: &str, key: &str) -> Result<()> {
    if d.get(name).is_some_and(|v| !v.is_null()) {
        return Ok(());
    }
    let section = match name {
        "camera" => d.get("reference_camera").cloned().unwrap_or_else(|| Value::Object(Map::new())),
        "estimate" => Value::Object(camera_at_start(d, key)?),
        _ => Value::Object(Map::new()),
    };
    d.insert(name.into(), section);
    Ok(())
}

fn lens_ratio(d: &mut Map<String, Value>, ratio: f64) -> Result<()> {
    let key = "lens_ratio";
    let reference = numbers_of(d.get("reference_camera").unwrap_or(&Value::Null), "reference_camera")?;
    let mut cam = match d.get("camera") {
        Some(c) if !c.is_null() => c.as_object().cloned().unwrap_or_default(),
        _ => reference.clone(),
    };
    let before = camera_at_start(d, key)?;
    let (fku, fkv) = (number(&reference, "fku", key)? * ratio, number(&reference, "fkv", key)? * ratio);
    cam.insert("fku".into(), json!(fku));
    cam.insert("fkv".into(), json!(fkv));
    let su = fku / number(&before, "fku", key)?;
    let sv = fkv / number(&before, "fkv", key)?;
    if let Some(Value::Object(zoom)) = cam.get_mut("zoom") {
        for (f, s) in [("fku", su), ("fkv", sv)] {
            if let Some(values) = floats(zoom.get(f)) {
                zoom.insert(f.into(), json!(values.iter().map(|v| v * s).collect::<Vec<f64>>()));
            }
        }
    }
    d.insert("camera".into(), Value::Object(cam));
    if let Some(est) = d.get("estimate").filter(|e| !e.is_null()) {
        let mut est = numbers_of(est, "estimate")?;
        let (efku, efkv) = (number(&est, "fku", key)? * su, number(&est, "fkv", key)? * sv);
        est.insert("fku".into(), json!(efku));
        est.insert("fkv".into(), json!(efkv));
        d.insert("estimate".into(), Value::Object(est));
    }
    Ok(())
}

/// K_hat: the base's estimate (its focal terms as numbers), or the servo camera at t = 0.
fn estimate_or(d: &Map<String, Value>, start: Map<String, Value>) -> Result<Map<String, Value>> {
    match d.get("estimate") {
        Some(e) if !e.is_null() => numbers_of(e, "estimate"),
        _ => Ok(start),
    }
}

fn focal_error(d: &mut Map<String, Value>, e: f64) -> Result<()> {
    let key = "focal_error";
    let cam0 = camera_at_start(d, key)?;
    let mut est = estimate_or(d, cam0.clone())?;
    est.insert("fku".into(), json!(number(&cam0, "fku", key)? * (1.0 + e)));
    est.insert("fkv".into(), json!(number(&cam0, "fkv", key)? * (1.0 + e)));
    d.insert("estimate".into(), Value::Object(est));
    Ok(())
}

fn principal_point_error(d: &mut Map<String, Value>, px: f64) -> Result<()> {
    let key = "principal_point_error";
    let has_estimate = d.get("estimate").is_some_and(|e| !e.is_null());
    let mut est = if has_estimate { estimate_or(d, Map::new())? } else { camera_at_start(d, key)? };
    for f in ["u0", "v0"] {
        est.insert(f.into(), json!(number(&est, f, key)? + px));
    }
    d.insert("estimate".into(), Value::Object(est));
    Ok(())
}

/// `x * (pi / 180)` and `x * (180 / pi)`, as NumPy's `radians` and `degrees` compute them.
fn radians(x: f64) -> f64 {
    x * (std::f64::consts::PI / 180.0)
}
fn degrees(x: f64) -> f64 {
    x * (180.0 / std::f64::consts::PI)
}

/// `a b` of 4x4 matrices with each entry a chain of fused multiply-adds from 0 in the order of
/// the inner index (as BLAS computes it: sweeps of earlier versions stay bit for bit).
fn fused_product(a: &Matrix4<f64>, b: &Matrix4<f64>) -> Matrix4<f64> {
    Matrix4::from_fn(|i, j| (0..4).fold(0.0, |acc: f64, k| a[(i, k)].mul_add(b[(k, j)], acc)))
}

/// R' = R Rz(roll), written back as theta-u degrees (angle in [0, 180]).
fn roll(d: &mut Map<String, Value>, deg: f64) -> Result<()> {
    let key = "roll_deg";
    let Some(Value::Object(start)) = d.get_mut("start") else {
        return Err(key_error(key, "the scenario has no [start] pose to roll"));
    };
    // rotation_deg (older files: rotation, read as degrees too)
    let thetau = match start.remove("rotation") {
        Some(Value::Array(r)) if !r.is_empty() => Value::Array(r),
        _ => start.get("rotation_deg").cloned().unwrap_or(json!([0.0, 0.0, 0.0])),
    };
    let t: Vec<f64> = thetau.as_array().map(|a| a.iter().filter_map(Value::as_f64).collect()).unwrap_or_default();
    let [x, y, z] = t[..] else { return Err(key_error(key, "start.rotation_deg: expected 3 numbers")) };
    let rotation = se3::pose_from_position_thetau([0.0; 3], [radians(x), radians(y), radians(z)])?;
    let rz = se3::pose_from_position_thetau([0.0; 3], [0.0, 0.0, deg.to_radians()])?;
    let rolled = se3::pose_from_matrix(&fused_product(&rotation.to_homogeneous(), &rz.to_homogeneous()))?;
    let tu = Vector3::from(se3::thetau_from_pose(&rolled)).map(degrees);
    start.insert("rotation_deg".into(), json!([tu.x, tu.y, tu.z]));
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, UnitQuaternion};

    fn lens() -> Map<String, Value> {
        let s = crate::sim::scenario::builtin("lens-12-6").unwrap();
        s.to_value().unwrap().as_object().unwrap().clone()
    }

    #[test]
    fn interp_is_numpys() {
        let (xp, fp) = ([0.0, 1.0, 3.0], [10.0, 20.0, 0.0]);
        assert_eq!([interp(-1.0, &xp, &fp), interp(0.0, &xp, &fp), interp(4.0, &xp, &fp)], [10.0, 10.0, 0.0]);
        assert_eq!([interp(0.5, &xp, &fp), interp(1.0, &xp, &fp), interp(2.0, &xp, &fp)], [15.0, 20.0, 10.0]);
    }

    #[test]
    fn the_fused_product_is_the_product_within_rounding() {
        let a = se3::pose_from_position_thetau([0.1, 0.2, 0.3], [0.4, -0.5, 0.6]).unwrap().to_homogeneous();
        let b = se3::pose_from_position_thetau([0.0; 3], [0.0, 0.0, 1.1]).unwrap().to_homogeneous();
        assert!((fused_product(&a, &b) - a * b).amax() < 1e-15);
    }

    /// R' = R Rz(a), checked against nalgebra's rotations; the focal terms by hand.
    #[test]
    fn roll_and_lens_keys_against_independent_computations() {
        let mut d = lens();
        let before: Vec<f64> = serde_json::from_value(d["start"]["rotation_deg"].clone()).unwrap();
        Derived::Roll.apply(&mut d, &json!(30.0)).unwrap();
        let after: Vec<f64> = serde_json::from_value(d["start"]["rotation_deg"].clone()).unwrap();
        let rot = |t: &[f64]| Rotation3::from_scaled_axis(Vector3::new(t[0], t[1], t[2]).map(f64::to_radians));
        let expected = rot(&before) * Rotation3::from_axis_angle(&Vector3::z_axis(), 30f64.to_radians());
        assert!((rot(&after).matrix() - expected.matrix()).amax() < 1e-12);
        assert!(UnitQuaternion::from_rotation_matrix(&rot(&after)).angle() <= std::f64::consts::PI);

        let mut d = lens();
        let cam = d["camera"].clone();
        Derived::FocalError.apply(&mut d, &json!(0.5)).unwrap();
        assert_eq!(d["estimate"]["fku"].as_f64().unwrap(), cam["fku"].as_f64().unwrap() * 1.5);
        // An estimate exists (the scenario's, kept by focal_error): its principal point moves.
        let u0 = d["estimate"]["u0"].as_f64().unwrap();
        assert_ne!(u0, cam["u0"].as_f64().unwrap());
        Derived::PrincipalPointError.apply(&mut d, &json!(2)).unwrap();
        assert_eq!(d["estimate"]["u0"].as_f64().unwrap(), u0 + 2.0);
        Derived::LensRatio.apply(&mut d, &json!(2.0)).unwrap();
        let fku_ref = d["reference_camera"]["fku"].as_f64().unwrap();
        assert_eq!(d["camera"]["fku"].as_f64().unwrap(), fku_ref * 2.0);
        let e = Derived::Roll.apply(&mut d, &json!("a")).unwrap_err().to_string();
        assert!(e.contains("vary key 'roll_deg': expected a finite number"), "{e}");
    }
}
