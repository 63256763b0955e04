//! The observed object: feature points and optional occluding bodies in a rapier3d-f64
//! world, and what a camera sees of them (projection, field of view, occlusion).

use nalgebra::{Isometry3, Point3};
use rapier3d_f64::prelude::{ColliderBuilder, PhysicsWorld, QueryFilter, Ray, RigidBodyBuilder, Vector};

use crate::core::camera::Intrinsics;
use crate::core::distortion::{Distortion, distort_normalised};
use crate::error::{Error, check_finite};
use crate::sim::error::Result;

/// A rigid body that can hide feature points (a plate or box carrying the dots, a ball, a
/// cylinder), fixed in F*.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// A box with half extents (metres) at a pose in F*.
    Cuboid {
        /// Half extents along the body axes.
        half_extents: [f64; 3],
        /// Body pose in F*.
        pose: Isometry3<f64>,
    },
    /// A ball.
    Ball {
        /// Radius in metres.
        radius: f64,
        /// Centre in F*.
        center: [f64; 3],
    },
    /// A cylinder along the body's y axis.
    Cylinder {
        /// Half height in metres.
        half_height: f64,
        /// Radius in metres.
        radius: f64,
        /// Body pose in F*.
        pose: Isometry3<f64>,
    },
}

/// What the camera sees of the points at one instant.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Observation {
    /// Pixels of all points (NaN where the point is behind the camera).
    pub pixels: Vec<[f64; 2]>,
    /// Depths of all points in the camera frame (metres, may be <= 0).
    pub depths: Vec<f64>,
    /// In front of the camera, inside the image and not occluded.
    pub visible: Vec<bool>,
}

/// Image bounds in pixels: `0 <= u < width`, `0 <= v < height`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageSize {
    /// Width in pixels.
    pub width: f64,
    /// Height in pixels.
    pub height: f64,
}

/// Points and occluders.
pub struct Scene {
    points: Vec<[f64; 3]>,
    world: Option<PhysicsWorld>,
    bodies: Vec<Body>,
    normals: Option<Vec<[f64; 3]>>,
    tags: Option<crate::vision::TagRig>,
}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene").field("points", &self.points).field("bodies", &self.bodies).finish()
    }
}

impl Clone for Scene {
    fn clone(&self) -> Self {
        // Rebuilding from validated parts cannot fail.
        Self {
            normals: self.normals.clone(),
            tags: self.tags.clone(),
            ..Self::build(self.points.clone(), self.bodies.clone())
        }
    }
}

/// Points closer to the camera plane than this (metres) count as behind the camera.
pub const MIN_DEPTH: f64 = 1e-6;

impl Scene {
    /// A scene of feature points (F*, metres) and occluding bodies.
    pub fn new(points: Vec<[f64; 3]>, bodies: Vec<Body>) -> Result<Self> {
        check_finite("object points", points.as_flattened())?;
        for (i, b) in bodies.iter().enumerate() {
            let (dims, ok): (Vec<f64>, bool) = match b {
                Body::Cuboid { half_extents, pose } => (
                    half_extents.to_vec(),
                    half_extents.iter().all(|&h| h > 0.0) && pose.translation.vector.iter().all(|v| v.is_finite()),
                ),
                Body::Ball { radius, center } => (vec![*radius], *radius > 0.0 && center.iter().all(|v| v.is_finite())),
                Body::Cylinder { half_height, radius, pose } => (
                    vec![*half_height, *radius],
                    *half_height > 0.0 && *radius > 0.0 && pose.translation.vector.iter().all(|v| v.is_finite()),
                ),
            };
            if !ok || dims.iter().any(|d| !d.is_finite()) {
                return Err(Error::InvalidParameter {
                    name: "object.bodies",
                    reason: format!("body {i}: sizes must be finite and > 0 and its pose finite"),
                }
                .into());
            }
        }
        Ok(Self::build(points, bodies))
    }

    fn build(points: Vec<[f64; 3]>, bodies: Vec<Body>) -> Self {
        let world = (!bodies.is_empty()).then(|| {
            let mut world = PhysicsWorld::new();
            for b in &bodies {
                let (collider, pose) = match b {
                    Body::Cuboid { half_extents: h, pose } => (ColliderBuilder::cuboid(h[0], h[1], h[2]), *pose),
                    Body::Ball { radius, center } => {
                        (ColliderBuilder::ball(*radius), Isometry3::translation(center[0], center[1], center[2]))
                    }
                    Body::Cylinder { half_height, radius, pose } => {
                        (ColliderBuilder::cylinder(*half_height, *radius), *pose)
                    }
                };
                world.insert(RigidBodyBuilder::fixed().pose(pose.into()), collider);
            }
            // One step builds the broad phase used by the ray casts; fixed bodies do not move.
            world.step();
            world
        });
        Self { points, world, bodies, normals: None, tags: None }
    }

    /// The same scene with a normal per point (F*; the orientation of each point's dot when
    /// images are rendered): one finite, non-zero normal per point.
    pub fn with_normals(mut self, normals: Vec<[f64; 3]>) -> Result<Self> {
        if normals.len() != self.points.len() {
            return Err(Error::Shape {
                what: "normals",
                expected: format!("one per point ({})", self.points.len()),
                got: normals.len().to_string(),
            }
            .into());
        }
        if let Some(i) = normals.iter().position(|n| !n.iter().all(|v| v.is_finite()) || n.iter().all(|&v| v == 0.0)) {
            return Err(Error::InvalidParameter {
                name: "normals",
                reason: format!("normal {i} must be finite and non-zero"),
            }
            .into());
        }
        self.normals = Some(normals);
        Ok(self)
    }

    /// The same scene shown as a rig of AprilTags: its points must be the tags' corners (four
    /// per tag, in order).
    pub fn with_tags(mut self, tags: crate::vision::TagRig) -> Result<Self> {
        use crate::vision::Target;
        let same = tags.points().len() == self.points.len()
            && tags.points().iter().zip(&self.points).all(|(t, p)| t.position == *p);
        if !same {
            return Err(Error::Shape {
                what: "tags",
                expected: format!("the scene's {} points as the tags' corners", self.points.len()),
                got: format!("{} corners", tags.points().len()),
            }
            .into());
        }
        self.tags = Some(tags);
        Ok(self)
    }

    /// The tag rig the scene shows, if any (None: dots).
    pub fn tags(&self) -> Option<&crate::vision::TagRig> {
        self.tags.as_ref()
    }

    /// The dots' normals, if given (None: each dot faces the reference camera).
    pub fn normals(&self) -> Option<&[[f64; 3]]> {
        self.normals.as_deref()
    }

    /// The feature points in F*.
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// The occluding bodies.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// Whether the segment from the camera centre to a point crosses a body.
    fn occluded(&self, center: &Point3<f64>, point: &Point3<f64>) -> bool {
        let Some(world) = &self.world else { return false };
        let d = point - center;
        let dist = d.norm();
        if dist <= 2e-6 {
            return false;
        }
        let dir = d / dist;
        let ray = Ray::new(Vector::new(center.x, center.y, center.z), Vector::new(dir.x, dir.y, dir.z));
        // Stop just short of the point, so that a dot on a face of its own plate is seen.
        world.cast_ray(&ray, dist - 1e-6, true, QueryFilter::default()).is_some()
    }

    /// Projects every point for a camera at `pose` (camera frame in F*) with intrinsics `k`
    /// and no distortion, and tells which points are visible, into `out` (reused to avoid
    /// allocations).
    pub fn observe(&self, pose: &Isometry3<f64>, k: &Intrinsics, image: Option<ImageSize>, out: &mut Observation) {
        self.observe_through(pose, k, &Distortion::none(), image, out);
    }

    /// [`Scene::observe`] through a lens: pixels `K d(m)`; a point beyond the distortion
    /// model's fold is not visible.
    pub fn observe_through(
        &self,
        pose: &Isometry3<f64>,
        k: &Intrinsics,
        distortion: &Distortion,
        image: Option<ImageSize>,
        out: &mut Observation,
    ) {
        let n = self.points.len();
        out.pixels.resize(n, [0.0; 2]);
        out.depths.resize(n, 0.0);
        out.visible.resize(n, false);
        // X_c = R^T (X - c): one rotation matrix for all points.
        let rt = pose.rotation.to_rotation_matrix().transpose();
        let km = k.matrix();
        let lens = !distortion.is_identity();
        let center = Point3::from(pose.translation.vector);
        for (i, p) in self.points.iter().enumerate() {
            let world_point = Point3::new(p[0], p[1], p[2]);
            let c = Point3::from(rt * (world_point - center));
            out.depths[i] = c.z;
            if c.z <= MIN_DEPTH {
                out.pixels[i] = [f64::NAN; 2];
                out.visible[i] = false;
                continue;
            }
            // None beyond the lens's fold or where the pixel overflows: not seen.
            let px = if lens {
                distort_normalised([c.x / c.z, c.y / c.z], k, distortion)
            } else {
                crate::core::camera::project_with(&km, &c).ok()
            };
            let Some(px) = px else {
                out.pixels[i] = [f64::NAN; 2];
                out.visible[i] = false;
                continue;
            };
            out.pixels[i] = px;
            let inside = image.is_none_or(|s| px[0] >= 0.0 && px[0] < s.width && px[1] >= 0.0 && px[1] < s.height);
            out.visible[i] = inside && !self.occluded(&center, &world_point);
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn through_a_lens_pixels_are_the_distorted_pinhole_pixels() {
        let points = vec![[0.0, 0.0, 1.0], [0.3, -0.2, 1.0], [0.25, 0.2, 0.8], [2.0, 0.0, 1.0]];
        let scene = Scene::new(points, vec![]).unwrap();
        let k = Intrinsics::pinhole(800.0, 790.0, 320.0, 240.0).unwrap();
        // k1 = -0.4 folds at r = 0.913: the last point (r = 2) is beyond the fold.
        let d = Distortion::from_coefficients(&[-0.4, 0.0, 0.001, -0.002]).unwrap();
        let (mut pinhole, mut lens) = (Observation::default(), Observation::default());
        let pose = Isometry3::translation(0.02, -0.01, 0.0);
        scene.observe(&pose, &k, None, &mut pinhole);
        scene.observe_through(&pose, &k, &d, None, &mut lens);
        let expected = crate::core::distortion::distort_points(&pinhole.pixels[..3], &k, &d).unwrap();
        for (p, q) in lens.pixels[..3].iter().zip(&expected) {
            assert!((p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9, "{p:?} vs {q:?}");
        }
        assert_eq!(lens.visible, vec![true, true, true, false]);
        assert!(lens.pixels[3][0].is_nan() && pinhole.visible[3]);
    }

    #[test]
    fn plate_hides_points_behind_it_but_not_its_own_dots() {
        let plate = Body::Cuboid { half_extents: [0.05, 0.05, 0.005], pose: Isometry3::translation(0.0, 0.0, 0.4) };
        let points = vec![[0.0, 0.0, 0.6], [0.0, 0.0, 0.395], [0.2, 0.0, 0.6], [0.0, 0.0, 0.405]];
        let scene = Scene::new(points, vec![plate]).unwrap();
        let k = Intrinsics::pinhole(800.0, 800.0, 320.0, 240.0).unwrap();
        let mut obs = Observation::default();
        scene.observe(&Isometry3::identity(), &k, Some(ImageSize { width: 640.0, height: 480.0 }), &mut obs);
        // behind the plate, on its front face, beside it, on its back face
        assert_eq!(obs.visible, vec![false, true, true, false]);
        // outside the image
        scene.observe(
            &Isometry3::translation(1.0, 0.0, 0.0),
            &k,
            Some(ImageSize { width: 640.0, height: 480.0 }),
            &mut obs,
        );
        assert!(obs.visible.iter().all(|v| !v));
        // behind the camera
        scene.observe(&Isometry3::translation(0.0, 0.0, 1.0), &k, None, &mut obs);
        assert!(obs.visible.iter().all(|v| !v) && obs.pixels[0][0].is_nan());
    }

    #[test]
    fn rejects_bad_bodies() {
        let bad = Body::Ball { radius: -1.0, center: [0.0; 3] };
        assert!(Scene::new(vec![[0.0, 0.0, 1.0]], vec![bad]).is_err());
        assert!(Scene::new(vec![[0.0, f64::NAN, 1.0]], vec![]).is_err());
    }
}
