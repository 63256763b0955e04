//! What a [`Target`](crate::vision::target::Target) draws with: a canvas over the noisy
//! background of one frame, seen by one camera, and its primitives. Today the primitive is a
//! white [`Disc`] of the object frame, and white convex [`Polygon`]s (the cells of a tag),
//! each with its `Shape` (`render/conic.rs`, `render/polygon.rs`; `render/raster.rs`).

use nalgebra::{Point3, Vector3};

use super::CameraView;
use super::conic::ImageEllipse;
use super::lens::Warp;
use super::polygon::{ImagePolygon, ImagePolygons};
use super::raster::{Paint, paint};
use super::texture::{TexturedFace, paint_faces};
use crate::error::{Error, Short};
use crate::vision::error::Result;
use crate::vision::image::GreyImage;

/// A white disc in the object frame (F*).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Centre, metres.
    pub center: Vector3<f64>,
    /// Unit normal of the disc's plane.
    pub normal: Vector3<f64>,
    /// Radius, metres.
    pub radius: f64,
}

impl Disc {
    /// A disc facing the reference camera: its normal points from the centre to the origin
    /// of F* (the default of scenario files).
    pub fn facing_reference(center: [f64; 3], radius: f64) -> Result<Self> {
        Self::new(center, [-center[0], -center[1], -center[2]], radius)
    }

    /// A disc with a given normal (normalised here).
    pub fn new(center: [f64; 3], normal: [f64; 3], radius: f64) -> Result<Self> {
        crate::error::check_finite("disc", &[center, normal].concat())?;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::InvalidParameter {
                name: "dot_radius",
                reason: format!("must be > 0, got {}", Short(radius)),
            }
            .into());
        }
        let normal = Vector3::from(normal);
        let largest = normal.amax();
        if !(largest > 1e-12) {
            return Err(Error::InvalidParameter { name: "normal", reason: "must not be zero".into() }.into());
        }
        // Scaled first: the norm of a normal of 1e300 overflows.
        let normal = normal / largest;
        Ok(Self { center: Vector3::from(center), normal: normal / normal.norm(), radius })
    }
}

/// A white planar convex polygon in the object frame (F*): its vertices in order around it.
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    vertices: Vec<Point3<f64>>,
}

impl Polygon {
    /// A polygon of at least 3 finite vertices (metres, F*), planar and convex (the caller's
    /// guarantee: a tag's cells are).
    pub fn new(vertices: Vec<[f64; 3]>) -> Result<Self> {
        crate::error::check_finite("polygon", vertices.as_flattened())?;
        if vertices.len() < 3 {
            let reason = format!("at least 3 vertices, got {}", vertices.len());
            return Err(Error::InvalidParameter { name: "polygon", reason }.into());
        }
        Ok(Self { vertices: vertices.into_iter().map(Point3::from).collect() })
    }

    /// The vertices.
    pub fn vertices(&self) -> &[Point3<f64>] {
        &self.vertices
    }
}

/// The image being drawn: one frame's noisy background, the camera that sees it, and the
/// primitives that draw on it (anti-aliased, blurred, with the frame's noise; overlapping
/// primitives take the brighter level).
pub struct Canvas<'a> {
    image: GreyImage,
    view: CameraView<'a>,
    warp: Warp,
    paint: Paint<'a>,
}

impl<'a> Canvas<'a> {
    pub(super) fn new(image: GreyImage, view: CameraView<'a>, paint: Paint<'a>) -> Self {
        let warp = Warp::new(view.intrinsics, view.distortion);
        Self { image, view, warp, paint }
    }

    /// The camera: pose in F*, intrinsics, distortion and image size.
    pub fn view(&self) -> &CameraView<'a> {
        &self.view
    }

    /// Fills a white disc; false when it is not drawn: not entirely in front of the camera,
    /// seen (nearly) edge-on, outside the image, or reaching beyond the lens model's fold.
    pub fn fill_disc(&mut self, disc: &Disc) -> bool {
        match ImageEllipse::of(disc, self.view.pose, self.view.intrinsics, &self.warp) {
            Some(ellipse) => paint(&mut self.image, &ellipse, &self.warp, &self.paint),
            None => false,
        }
    }

    /// Fills a white convex polygon; false when it is not drawn (as [`Canvas::fill_polygons`]).
    pub fn fill_polygon(&mut self, polygon: &Polygon) -> bool {
        self.fill_polygons(std::slice::from_ref(polygon))
    }

    /// Fills white convex polygons that do not overlap (they may share edges: the cells of a
    /// tag), as one shape: the coverage of a pixel is the exact area of the polygons in it, so
    /// a shared edge leaves no seam. False (nothing drawn) when a polygon is not entirely in
    /// front of the camera or reaches beyond the lens model's fold, or when all fall outside
    /// the image; a polygon seen edge-on is skipped.
    pub fn fill_polygons(&mut self, polygons: &[Polygon]) -> bool {
        let mut images = Vec::with_capacity(polygons.len());
        for polygon in polygons {
            match self.polygon_image(polygon) {
                Some(Some(image)) => images.push(image),
                Some(None) => {}
                None => return false,
            }
        }
        !images.is_empty() && paint(&mut self.image, &ImagePolygons { polygons: images }, &self.warp, &self.paint)
    }

    /// Draws textured faces (their grey levels replace the background; faces turned away
    /// are culled, the nearest face shows); per face, whether it is drawn (seen from its
    /// front, in front of the camera, its image meeting the image).
    pub fn draw_textured_faces(&mut self, faces: &[TexturedFace]) -> Vec<bool> {
        paint_faces(&mut self.image, faces, (self.view.pose, self.view.intrinsics), &self.warp, &self.paint)
    }

    /// The image of a polygon: None when it cannot be drawn, Some(None) when seen edge-on.
    fn polygon_image(&self, polygon: &Polygon) -> Option<Option<ImagePolygon>> {
        ImagePolygon::of(&polygon.vertices, self.view.pose, self.view.intrinsics, &self.warp)
    }

    pub(super) fn into_image(self) -> GreyImage {
        self.image
    }
}
