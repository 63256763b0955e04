//! A run's record in bounded memory. The record keeps one row per iteration; a run of
//! `stop.max_iterations = 10_000_000` with a stop rule never met would need gigabytes (issue
//! 28: it aborted on memory after 29 s). The record holds at most `SimulationConfig::
//! record_bytes` ([`MAX_RECORD_BYTES`] by default): when full, every other row is dropped and
//! from then on one iteration in `stride` is kept (the stride doubles each time). The first
//! row (the start) and the last row (where the run ended) are always kept; the `time`
//! column says which iterations the rows are. Runs that fit are recorded whole.

use crate::sim::outcome::Recording;

/// The most memory a run's record holds by default, bytes (about 100,000 rows of 12 points).
pub const MAX_RECORD_BYTES: usize = 64 << 20;

/// Which iterations a record keeps (module docs).
#[derive(Debug, Clone)]
pub(crate) struct RecordBudget {
    max_rows: usize,
    stride: usize,
    /// The last row is kept only as the latest one (its iteration is off the stride).
    provisional: bool,
}

impl RecordBudget {
    /// The budget of `bytes` for rows of `n_points` points and `n_joints` joints, with or
    /// without the per-point detection column: at least 3 rows.
    pub(crate) fn new(bytes: usize, n_points: usize, n_joints: usize, images: bool) -> Self {
        // f64 columns: time, pose 16, twist 6, joints and joint velocities, pixels 2n, the
        // errors (invariant, tracking, eps 5, eps_z, image, translation, rotation), detection n.
        let floats = 1 + 16 + 6 + 2 * n_joints + 2 * n_points + 11 + if images { n_points } else { 0 };
        let row = 8 * floats + n_points; // + visibility
        Self { max_rows: (bytes / row).max(3), stride: 1, provisional: false }
    }

    /// Makes room for the row of `iteration` (called before it is recorded, when every column
    /// of `r` holds the same number of rows).
    pub(crate) fn before_row(&mut self, r: &mut Recording, iteration: usize) {
        if self.provisional {
            r.drop_last_row();
        }
        while r.len() >= self.max_rows {
            // Keeps rows 0, 2, 4, ...: iterations on the doubled stride.
            r.keep_rows(1, |i| i % 2 == 0);
            self.stride *= 2;
        }
        self.provisional = !iteration.is_multiple_of(self.stride);
    }
}

impl Recording {
    /// Drops the last row of every column (the work of one row).
    fn drop_last_row(&mut self) {
        let rows = self.len();
        if rows > 0 {
            self.keep_rows(rows - 1, |i| i < rows - 1);
        }
    }

    /// Keeps, in every column, the rows `i >= from` for which `keep(i)` (the rows before
    /// `from` stay where they are).
    fn keep_rows(&mut self, from: usize, keep: impl Fn(usize) -> bool) {
        let rows = self.len();
        if rows == 0 {
            return;
        }
        // Every column by name (no `..`): a new column cannot be forgotten here.
        let Self {
            n_points: _,
            n_joints: _,
            time,
            pose,
            twist,
            joints,
            joint_velocities,
            pixels,
            visible,
            invariant_error,
            tracking_error,
            eps,
            eps_z,
            image_error,
            translation_error,
            rotation_error,
            detection_error,
        } = self;
        retain_rows(visible, rows, from, &keep);
        for column in [
            time,
            pose,
            twist,
            joints,
            joint_velocities,
            pixels,
            invariant_error,
            tracking_error,
            eps,
            eps_z,
            image_error,
            translation_error,
            rotation_error,
            detection_error,
        ] {
            retain_rows(column, rows, from, &keep);
        }
    }
}

/// Keeps the rows `i >= from` of `column` (`rows` rows of equal width) for which `keep(i)`.
fn retain_rows<T: Copy>(column: &mut Vec<T>, rows: usize, from: usize, keep: &impl Fn(usize) -> bool) {
    let width = column.len() / rows;
    let mut out = from;
    for i in (from..rows).filter(|&i| keep(i)) {
        column.copy_within(i * width..(i + 1) * width, out * width);
        out += 1;
    }
    column.truncate(out * width);
}
