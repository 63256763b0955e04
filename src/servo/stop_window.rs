//! The stop rules' averaging window.

/// The stop rules' low-pass filter: the error *vectors* (`tau_21`, `s - s*`, `p - p*`, NaN
/// for hidden points) averaged over the last `window` images, so that zero-mean pixel noise
/// averages out instead of adding up in a norm.
pub(crate) struct StopWindow {
    window: usize,
    rows: std::collections::VecDeque<Vec<f64>>,
    mean: Vec<f64>,
}

impl StopWindow {
    pub(crate) fn new(window: usize) -> Self {
        Self { window, rows: std::collections::VecDeque::with_capacity(window.min(1024) + 1), mean: Vec::new() }
    }

    /// A row to fill with [`measure`] (the oldest row, recycled, once the window is full).
    pub(crate) fn next_row(&mut self) -> Vec<f64> {
        let mut row =
            if self.rows.len() == self.window { self.rows.pop_front().unwrap_or_default() } else { Vec::new() };
        row.clear();
        row
    }

    /// The means returned by the last [`push`](Self::push) (None before the window is full).
    pub(crate) fn mean(&self) -> Option<&[f64]> {
        match self.window {
            _ if self.rows.len() < self.window => None,
            1 => self.rows.back().map(Vec::as_slice),
            _ => Some(&self.mean),
        }
    }

    /// Adds the errors of one image; returns the means once the window is full.
    pub(crate) fn push(&mut self, row: Vec<f64>) -> Option<&[f64]> {
        self.rows.push_back(row);
        if self.rows.len() < self.window {
            return None;
        }
        if self.window == 1 {
            return self.rows.front().map(Vec::as_slice);
        }
        let len = self.rows[0].len();
        self.mean.clear();
        self.mean.resize(len, 0.0);
        for r in &self.rows {
            self.mean.iter_mut().zip(r).for_each(|(m, v)| *m += v);
        }
        let w = self.window as f64;
        self.mean.iter_mut().for_each(|m| *m /= w);
        Some(&self.mean)
    }
}
