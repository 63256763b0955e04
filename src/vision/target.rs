//! What the camera looks at: a target is a set of points with identities (what a detector
//! reports and the control law servoes on) and a way to draw itself with the renderer's
//! primitives: [`Dots`](dots::Dots), one white disc per point, and [`TagRig`](tags::TagRig), a rig
//! of AprilTags (their corners as points, their white cells as filled polygons).

pub mod dots;
pub mod features;
pub mod tags;

use crate::vision::render::{Canvas, Drawing};

/// A point of a target: its identity and its position in the object frame (F*).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetPoint {
    /// Unique within the target: the identity a [`Detector`](crate::vision::detector::Detector)
    /// reports the point under (a tag's corner `c` of tag `t` could be `4 t + c`).
    pub id: u32,
    /// Position, metres, in the object frame.
    pub position: [f64; 3],
}

/// Something the camera sees: points with identities, drawn by the renderer's primitives.
pub trait Target: Send + Sync {
    /// The points, in the order of the scene's points (the order of the caller's flags and
    /// of [`Rendered::drawn`](crate::vision::render::Rendered::drawn)).
    fn points(&self) -> &[TargetPoint];

    /// Draws the target on `canvas` (which knows the camera); `visible` (None: all, else one
    /// flag per point, checked by the renderer) hides occluded points. Returns, per point,
    /// whether it was drawn.
    fn draw(&self, canvas: &mut Canvas<'_>, visible: Option<&[bool]>) -> Vec<bool>;
}

/// Every target is drawn by the renderer (which knows only [`Drawing`]).
impl<T: Target + ?Sized> Drawing for T {
    fn point_count(&self) -> usize {
        self.points().len()
    }

    fn draw_on(&self, canvas: &mut Canvas<'_>, visible: Option<&[bool]>) -> Vec<bool> {
        self.draw(canvas, visible)
    }
}

/// Whether point `i` is to be drawn under `visible` (a missing flag hides it).
pub fn shown(visible: Option<&[bool]>, i: usize) -> bool {
    visible.is_none_or(|v| v.get(i).copied().unwrap_or(false))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use nalgebra::Isometry3;

    use super::*;
    use crate::core::camera::Intrinsics;
    use crate::core::distortion::Distortion;
    use crate::vision::render::{CameraView, Disc, RenderConfig, Renderer};

    /// A test target: each point is drawn as a pair of small discs side by side (3 mm apart),
    /// and its identities are not its indices.
    struct Pairs {
        points: Vec<TargetPoint>,
    }

    impl Target for Pairs {
        fn points(&self) -> &[TargetPoint] {
            &self.points
        }

        fn draw(&self, canvas: &mut Canvas<'_>, visible: Option<&[bool]>) -> Vec<bool> {
            let mut drawn = Vec::new();
            for (i, p) in self.points.iter().enumerate() {
                let [x, y, z] = p.position;
                let mut both = shown(visible, i);
                for dx in [-0.003, 0.003] {
                    let disc = Disc::new([x + dx, y, z], [0.0, 0.0, -1.0], 0.001).unwrap();
                    both = both && canvas.fill_disc(&disc);
                }
                drawn.push(both);
            }
            drawn
        }
    }

    #[test]
    fn any_target_is_drawn_by_the_renderer_primitives() {
        let config = RenderConfig {
            blur_sigma: 0.0,
            noise_sigma: 0.0,
            background: 10,
            foreground: 210,
            seed: 0,
            dot_radius: 0.001,
            polarity: crate::vision::Polarity::Light,
        };
        let renderer = Renderer::new(config).unwrap();
        let k = Intrinsics::pinhole(1000.0, 1000.0, 50.0, 40.0).unwrap();
        let (pose, none) = (Isometry3::identity(), Distortion::none());
        let view = CameraView { pose: &pose, intrinsics: &k, distortion: &none, size: (100, 80) };
        let position = |x: f64| [x, 0.0, 0.5];
        let target = Pairs {
            points: vec![
                TargetPoint { id: 7, position: position(-0.02) },
                TargetPoint { id: 3, position: position(0.02) },
                TargetPoint { id: 11, position: position(5.0) },
            ],
        };
        let out = renderer.render(&target, None, &view, 0).unwrap();
        // The third pair is far outside the image.
        assert_eq!(out.drawn, vec![true, true, false]);
        // Pair of point 7: discs of radius 2 px at u = 50 - 40 -/+ 6 = 4 and 16, row 40.
        let at = |u: u32| out.image.get_pixel(u, 40)[0];
        assert_eq!((at(4), at(10), at(16)), (210, 10, 210));
        let hidden = renderer.render(&target, Some(&[false, true, true]), &view, 0).unwrap();
        assert_eq!(hidden.drawn, vec![false, true, false]);
        assert_eq!(hidden.image.get_pixel(4, 40)[0], 10);
        // One flag per point, for the mask as for what the target returns.
        assert!(renderer.render(&target, Some(&[true]), &view, 0).is_err());
        struct Liar;
        impl Target for Liar {
            fn points(&self) -> &[TargetPoint] {
                &[]
            }
            fn draw(&self, _: &mut Canvas<'_>, _: Option<&[bool]>) -> Vec<bool> {
                vec![true]
            }
        }
        assert!(renderer.render(&Liar, None, &view, 0).is_err());
    }
}
