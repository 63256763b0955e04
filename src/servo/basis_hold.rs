//! Riding out a basis point's short loss. The invariant points `q_k = Q^-1 m_k` (sec. 2.2,
//! eq. 5) are defined by the basis's three points, whose matrix `Q` must be invertible: an
//! image without one of them has no invariant point at all, and a new basis moves the error
//! `e = s - s*` (eq. 10) to another space, where the controller starts afresh. A keypoint's
//! track that fails its checks for a frame or two would otherwise switch the basis back and
//! forth; the session instead keeps its basis and repeats its last twist for up to `limit`
//! consecutive images, judging no stop on them.

use nalgebra::Vector6;

/// The state of the hold: whether the current image is ridden out, and the twist it repeats.
#[derive(Debug, Clone)]
pub(crate) struct BasisHold {
    limit: usize,
    /// The basis has been fully in view since it was chosen.
    seen: bool,
    /// Consecutive images with a basis point missing.
    missing: usize,
    held: bool,
    last_twist: Vector6<f64>,
    images: usize,
}

impl BasisHold {
    /// A hold of at most `limit` consecutive images (0: none).
    pub(crate) fn new(limit: usize) -> Self {
        Self { limit, seen: false, missing: 0, held: false, last_twist: Vector6::zeros(), images: 0 }
    }

    /// Takes an image in which the basis is fully in view (`all_visible`) or not; returns
    /// whether the image is ridden out (a point missing for at most `limit` images of a basis
    /// seen before). `false` with a point missing means the basis must change.
    pub(crate) fn observe(&mut self, all_visible: bool) -> bool {
        if all_visible {
            (self.seen, self.missing, self.held) = (true, 0, false);
            return false;
        }
        self.missing += 1;
        self.held = self.seen && self.missing <= self.limit;
        self.images += usize::from(self.held);
        self.held
    }

    /// Not ridden out (too few points to hold anything with).
    pub(crate) fn release(&mut self) {
        self.held = false;
    }

    /// A new basis, chosen among the points in view: seen, nothing missing.
    pub(crate) fn rebased(&mut self) {
        (self.seen, self.missing, self.held) = (true, 0, false);
    }

    /// The current image is ridden out.
    pub(crate) fn holding(&self) -> bool {
        self.held
    }

    /// The twist a held image repeats: the last one the law gave (zero before any).
    pub(crate) fn twist(&self) -> Vector6<f64> {
        self.last_twist
    }

    /// The law's twist on an image with the basis in view.
    pub(crate) fn record(&mut self, twist: Vector6<f64>) {
        self.last_twist = twist;
    }

    /// Images ridden out so far.
    pub(crate) fn images(&self) -> usize {
        self.images
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A loss of up to `limit` images is held, a longer one is not, a basis never seen is not
    /// held, and the count restarts when the basis is back.
    #[test]
    fn holds_short_losses_of_a_seen_basis_only() {
        let mut h = BasisHold::new(2);
        assert!(!h.observe(false), "never seen: change at once");
        h.rebased();
        assert!(h.observe(false) && h.holding());
        assert!(h.observe(false));
        assert!(!h.observe(false), "third image missing: beyond the limit");
        h.rebased();
        assert!(h.observe(false));
        assert!(!h.observe(true) && !h.holding());
        assert!(h.observe(false) && h.observe(false), "the count restarted");
        assert_eq!(h.images(), 5);
        let mut none = BasisHold::new(0);
        none.rebased();
        assert!(!none.observe(false), "limit 0: no hold");
        h.record(Vector6::repeat(0.5));
        assert_eq!(h.twist(), Vector6::repeat(0.5));
    }
}
