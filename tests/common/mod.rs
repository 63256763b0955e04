//! Scene helpers shared by the integration tests: an object, poses, a pinhole view, and a
//! tiny deterministic random generator (the tests must be reproducible).
#![allow(clippy::unwrap_used, clippy::expect_used)]
#![allow(dead_code)]

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use vsinv::Intrinsics;

/// Deterministic generator (64-bit LCG) for reproducible random draws.
pub struct Lcg(pub u64);

impl Lcg {
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// Twelve points in a 300 x 240 mm area about 600 mm in front of F*, with +-60 mm relief
/// (the paper's object of sec. 5.2 is "close to planar").
pub fn object_points() -> Vec<[f64; 3]> {
    let mut pts = Vec::new();
    let xs = [-0.15, -0.05, 0.05, 0.15];
    let ys = [-0.12, 0.0, 0.12];
    let relief = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03, 0.04, -0.05, 0.01, 0.06];
    let mut r = 0;
    for y in ys {
        for x in xs {
            pts.push([x, y, 0.6 + relief[r]]);
            r += 1;
        }
    }
    pts
}

/// The paper's 12 mm lens at 100 px/mm on a 768 x 576 sensor, with a skew option.
pub fn lens(focal_px: f64) -> Intrinsics {
    Intrinsics::pinhole(focal_px, focal_px, 384.0, 288.0).unwrap()
}

/// Pixels and depths of `object` (in F*) seen from the camera at `pose` (camera in F*).
pub fn view(object: &[[f64; 3]], pose: &Isometry3<f64>, k: &Intrinsics) -> (Vec<[f64; 2]>, Vec<f64>) {
    let inv = pose.inverse();
    let cam: Vec<[f64; 3]> = object
        .iter()
        .map(|p| {
            let c = inv * Point3::new(p[0], p[1], p[2]);
            [c.x, c.y, c.z]
        })
        .collect();
    vsinv::project_points(&cam, k).unwrap()
}

/// Camera at `center` looking at `target`, then rolled by `roll` about its optical axis.
pub fn look_at(center: [f64; 3], target: [f64; 3], roll: f64) -> Isometry3<f64> {
    let z = (Vector3::from(target) - Vector3::from(center)).normalize();
    let rot = Rotation3::rotation_between(&Vector3::z(), &z).unwrap_or_else(Rotation3::identity);
    let q = UnitQuaternion::from_rotation_matrix(&rot) * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), roll);
    Isometry3::from_parts(Translation3::from(Vector3::from(center)), q)
}

/// A random pose near F* that still sees the object.
pub fn random_pose(rng: &mut Lcg, trans: f64, rot: f64) -> Isometry3<f64> {
    let t = Vector3::new(rng.uniform(-trans, trans), rng.uniform(-trans, trans), rng.uniform(-trans, trans));
    let r = Vector3::new(rng.uniform(-rot, rot), rng.uniform(-rot, rot), rng.uniform(-rot, rot));
    Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_scaled_axis(r))
}

/// Random upper-triangular intrinsics: skewed, non-square pixels, shifted principal point.
pub fn random_intrinsics(rng: &mut Lcg) -> Intrinsics {
    Intrinsics::new(
        rng.uniform(300.0, 3000.0),
        rng.uniform(300.0, 3000.0),
        rng.uniform(-200.0, 900.0),
        rng.uniform(-200.0, 700.0),
        rng.uniform(1.2, 1.9),
    )
    .unwrap()
}

/// Integrates a controller in closed loop with the exact SE(3) exponential; returns the final
/// pose and the number of iterations run.
pub fn integrate<F>(start: Isometry3<f64>, dt: f64, iterations: usize, mut law: F) -> (Isometry3<f64>, usize)
where
    F: FnMut(&Isometry3<f64>, usize) -> Option<[f64; 6]>,
{
    let mut pose = start;
    for i in 0..iterations {
        match law(&pose, i) {
            Some(tw) => pose *= vsinv::core::se3::exp_twist(&tw.map(|x| x * dt)).expect("a finite motion"),
            None => return (pose, i),
        }
    }
    (pose, iterations)
}

/// Twelve points on a 4 x 3 grid, 300 x 240 mm, about 600 mm in front of F*, with +-60 mm of
/// relief: the servo session's tests of partial targets and of the stall rule.
pub fn grid_object() -> Vec<[f64; 3]> {
    let relief = [0.0, 0.06, -0.04, 0.03, -0.06, 0.05, 0.02, -0.03, 0.04, -0.05, 0.01, -0.02];
    (0..12).map(|i| [-0.15 + 0.1 * (i % 4) as f64, -0.12 + 0.12 * (i / 4) as f64, 0.6 + relief[i]]).collect()
}

/// The pixels of [`grid_object`] seen from `pose` (camera in the object's frame) through `k`.
pub fn grid_view(pose: &Isometry3<f64>, k: &Intrinsics) -> Vec<[f64; 2]> {
    let inv = pose.inverse();
    grid_object().iter().map(|p| k.project(&(inv * Point3::from(*p))).unwrap().0).collect()
}
