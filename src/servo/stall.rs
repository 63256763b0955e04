//! The stall rule (issue 27): real detections of one pose by two different lenses disagree
//! (detection biases), so the invariant error settles at a floor above any fixed threshold.
//! The loop has then done all it can when the error has stopped decreasing and the commanded
//! twist would move the camera by a small fraction of the pose tolerance over the window; the
//! pose uncertainty, with the measured disagreement floor, then decides `converged` or
//! `settled` ([`super::session::Servo::verdict`]).

use std::collections::VecDeque;

use nalgebra::Vector6;

use crate::servo::stop::StopRules;
use crate::servo::stop_window::StopWindow;

/// The error has "stopped decreasing" when the mean over the window's last half is at least
/// this fraction of the mean over its first half (a decrease of less than 10 %). Exponential
/// convergence at gain lambda decreases it by `1 - exp(-lambda T / 2)` over a window of `T`
/// seconds (39 % at lambda = 1/s, T = 1 s), so only a loop at its floor passes.
pub const STALL_DECREASE: f64 = 0.9;

/// The last `stall_window` errors and twists, and the error rows averaged over them (the
/// images the floor and the pose uncertainty are then measured on).
pub(crate) struct StallWatch {
    errors: VecDeque<f64>,
    twists: VecDeque<Vector6<f64>>,
    pub(crate) rows: StopWindow,
    window: usize,
}

impl StallWatch {
    pub(crate) fn new(window: usize) -> Self {
        Self { errors: VecDeque::new(), twists: VecDeque::new(), rows: StopWindow::new(window), window }
    }

    /// Forgets everything (a new basis: new errors).
    pub(crate) fn reset(&mut self) {
        *self = Self::new(self.window);
    }

    /// The rule's error of the last image.
    pub(crate) fn push_error(&mut self, error: f64) {
        push(&mut self.errors, error, self.window);
    }

    /// The twist commanded on the last image.
    pub(crate) fn push_twist(&mut self, twist: Vector6<f64>) {
        push(&mut self.twists, twist, self.window);
    }

    /// Whether the loop has stalled: a full window of finite errors that stopped decreasing
    /// ([`STALL_DECREASE`]), and a mean commanded twist that would move the camera, over the
    /// window (`window * dt` seconds), by less than `stall_motion` times the pose tolerance in
    /// translation and in rotation. The mean twist, not each twist: pixel noise makes the
    /// twists jitter with zero mean, which moves the camera nowhere; a tenth of the tolerance
    /// (the default) means that going on could gain at most a tenth of what the tolerance
    /// allows per window, while the floor keeps the error where it is.
    pub(crate) fn stalled(&self, stop: &StopRules, dt: f64) -> bool {
        let w = self.window;
        if self.errors.len() < w || self.twists.len() < w || self.errors.iter().any(|e| !e.is_finite()) {
            return false;
        }
        let half = w / 2;
        let first = self.errors.iter().take(half).sum::<f64>() / half as f64;
        let last = self.errors.iter().skip(w - half).sum::<f64>() / half as f64;
        let mean = self.twists.iter().sum::<Vector6<f64>>() / w as f64;
        let seconds = w as f64 * dt;
        let moves = mean.fixed_rows::<3>(0).norm() * seconds;
        let turns = mean.fixed_rows::<3>(3).norm() * seconds;
        last >= STALL_DECREASE * first
            && moves < stop.stall_motion * stop.max_translation_uncertainty
            && turns < stop.stall_motion * stop.max_rotation_uncertainty_deg.to_radians()
    }
}

fn push<T>(queue: &mut VecDeque<T>, value: T, window: usize) {
    if queue.len() == window {
        queue.pop_front();
    }
    queue.push_back(value);
}
