//! Today's target: one white disc per point (a radius, a normal), the point its centre.

use crate::vision::error::Result;
use crate::vision::render::{Canvas, Disc};
use crate::vision::target::{Target, TargetPoint, shown};

/// White discs on a dark background; point `i` (identity `i`) is the centre of disc `i`.
#[derive(Debug, Clone, PartialEq)]
pub struct Dots {
    discs: Vec<Disc>,
    points: Vec<TargetPoint>,
}

impl Dots {
    /// The dots of some discs, identities `0, 1, ...` in their order.
    pub fn new(discs: Vec<Disc>) -> Self {
        let points = (0u32..)
            .zip(&discs)
            .map(|(id, d)| TargetPoint { id, position: [d.center.x, d.center.y, d.center.z] })
            .collect();
        Self { discs, points }
    }

    /// Discs of `radius` at `points` (F*), facing the reference camera.
    pub fn facing_reference(points: &[[f64; 3]], radius: f64) -> Result<Self> {
        Ok(Self::new(points.iter().map(|&p| Disc::facing_reference(p, radius)).collect::<Result<_>>()?))
    }

    /// The discs.
    pub fn discs(&self) -> &[Disc] {
        &self.discs
    }
}

impl Target for Dots {
    fn points(&self) -> &[TargetPoint] {
        &self.points
    }

    fn draw(&self, canvas: &mut Canvas<'_>, visible: Option<&[bool]>) -> Vec<bool> {
        self.discs.iter().enumerate().map(|(i, disc)| shown(visible, i) && canvas.fill_disc(disc)).collect()
    }
}
