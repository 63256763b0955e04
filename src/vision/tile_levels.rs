//! The levels of a tile of the dots' local threshold ([`background`](super::background)) from
//! its neighbourhood of tiles: the tile's size, the lower quartile of the medians around it
//! (the background), the largest peak around it, and the threshold between the two. Read by
//! the fine tiles ([`background`](super::background)) and the coarser levels
//! ([`coarse`](super::coarse)) alike.

/// Side of a tile, pixels.
pub const TILE: u32 = 32;
/// Tiles on each side of a tile in its background neighbourhood (5 x 5 tiles).
pub const BACKGROUND_REACH: usize = 2;
/// Tiles on each side of a tile in its peak neighbourhood (3 x 3 tiles).
pub const PEAK_REACH: usize = 1;

/// Half way between the background `b` and the peak `p`, at least `min_contrast` above `b`.
pub(crate) fn threshold(b: u8, p: u8, min_contrast: u8) -> u8 {
    b.saturating_add((p.saturating_sub(b) / 2).max(min_contrast))
}

/// Whether the neighbourhood of a tile shows no contrast beyond `min_contrast` (its threshold
/// is `b + min_contrast`): a plain background, or the inside of a dot larger than the
/// neighbourhood.
pub(crate) fn flat(b: u8, p: u8, min_contrast: u8) -> bool {
    p.saturating_sub(b) / 2 <= min_contrast
}

/// The rows and columns of the tiles within `reach` tiles of `(row, column)`, clipped to the
/// grid.
fn neighbourhood(
    columns: usize,
    rows: usize,
    row: usize,
    column: usize,
    reach: usize,
) -> (std::ops::RangeInclusive<usize>, std::ops::RangeInclusive<usize>) {
    let (r0, r1) = (row.saturating_sub(reach), (row + reach).min(rows - 1));
    let (c0, c1) = (column.saturating_sub(reach), (column + reach).min(columns - 1));
    (r0..=r1, c0..=c1)
}

/// Values of a neighbourhood, padded with 255 (above any candidate of [`order_statistic`]).
const AROUND: usize = 32;

/// The lower quartile of the tile medians around a tile ([`BACKGROUND_REACH`] tiles on each
/// side).
pub(crate) fn lower_quartile(medians: &[u8], columns: usize, rows: usize, row: usize, column: usize) -> u8 {
    const { assert!((2 * BACKGROUND_REACH + 1) * (2 * BACKGROUND_REACH + 1) <= AROUND) };
    let mut around = [u8::MAX; AROUND];
    let (rs, cs) = neighbourhood(columns, rows, row, column, BACKGROUND_REACH);
    let mut n = 0;
    for r in rs {
        for c in cs.clone() {
            around[n] = medians[r * columns + c];
            n += 1;
        }
    }
    order_statistic(&around, (n - 1) / 4)
}

/// The `k`-th smallest of `values` (from 0): the largest `m` with at most `k` values below
/// it, built from its highest bit down (the value a sort would put at `k`; the counts
/// vectorise).
fn order_statistic(values: &[u8; AROUND], k: usize) -> u8 {
    let mut m = 0u8;
    for bit in (0..8).rev() {
        let candidate = m | (1 << bit);
        // Counted in bytes (at most AROUND): one byte lane per value.
        let below = values.iter().fold(0u8, |n, &x| n.wrapping_add(u8::from(x < candidate)));
        if usize::from(below) <= k {
            m = candidate;
        }
    }
    m
}

/// The largest peak around a tile ([`PEAK_REACH`] tiles on each side).
pub(crate) fn largest(peaks: &[u8], columns: usize, rows: usize, row: usize, column: usize) -> u8 {
    let (rs, cs) = neighbourhood(columns, rows, row, column, PEAK_REACH);
    rs.map(|r| peaks[r * columns + cs.start()..=r * columns + cs.end()].iter().copied().max().unwrap_or(0))
        .max()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_statistics_are_those_of_a_sort() {
        let mut state = 3u64;
        for n in 1..=25 {
            for spread in [4u64, 256] {
                let mut values = [u8::MAX; AROUND];
                for x in &mut values[..n] {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    *x = ((state >> 33) % spread) as u8 * if spread == 4 { 60 } else { 1 };
                }
                let mut sorted = values[..n].to_vec();
                sorted.sort_unstable();
                for (k, &expected) in sorted.iter().enumerate() {
                    assert_eq!(order_statistic(&values, k), expected, "n {n}, k {k}: {sorted:?}");
                }
            }
        }
    }
}
