//! Which transponder to interrogate next (paper 003 §V-D).
//!
//! The figure of merit of transponder `k` is
//!
//! ```text
//! m_k = ‖(x − x_k, y − y_k)‖²_{P_xy} / ((x − x_k)² + (y − y_k)²)
//! ```
//!
//! the position's variance along the direction to the transponder: a range
//! to the transponder with the largest `m_k` shrinks the ellipse most where
//! it is longest. `selection = "round-robin"` asks each in turn instead.

use crate::lbl::layout::Layout;
use crate::lbl::params::Selection;

/// `m_k` at the position `(x, y)` with covariance `P_xy` for a transponder
/// at `(x_k, y_k)`; 0 on top of it (no direction).
pub fn figure_of_merit(x: f64, y: f64, p_xy: [[f64; 2]; 2], x_k: f64, y_k: f64) -> f64 {
    let (dx, dy) = (x - x_k, y - y_k);
    let d2 = dx * dx + dy * dy;
    if !(d2 > 0.0) {
        return 0.0;
    }
    let quad = dx * (p_xy[0][0] * dx + p_xy[0][1] * dy) + dy * (p_xy[1][0] * dx + p_xy[1][1] * dy);
    quad / d2
}

/// The index in `layout` of the next transponder to interrogate: the
/// largest `m_k` (the first of equal ones), or `*next_in_turn` (then moved
/// on) for round robin.
pub fn next(
    selection: Selection,
    layout: &Layout,
    position: [f64; 2],
    p_xy: [[f64; 2]; 2],
    next_in_turn: &mut usize,
) -> usize {
    let n = layout.len();
    match selection {
        Selection::RoundRobin => {
            let i = *next_in_turn % n;
            *next_in_turn = (i + 1) % n;
            i
        }
        Selection::FigureOfMerit => {
            let mut best = (0, f64::NEG_INFINITY);
            for (i, t) in layout.transponders().iter().enumerate() {
                let m = figure_of_merit(position[0], position[1], p_xy, t.north_m, t.east_m);
                if m > best.1 {
                    best = (i, m);
                }
            }
            best.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lbl::layout::preset;

    #[test]
    fn the_figure_of_merit_picks_the_long_axis() {
        let layout = Layout::new(preset("Four").expect("four")).expect("layout");
        // On the box's west side, the ellipse long north-south: one of the
        // western transponders, whose line of sight is more north-south.
        let p = [[25.0, 0.0], [0.0, 1.0]];
        let pos = [250.0, 0.0];
        let mut turn = 0;
        let i = next(Selection::FigureOfMerit, &layout, pos, p, &mut turn);
        let t = &layout.transponders()[i];
        let dir = ((pos[0] - t.north_m).abs(), (pos[1] - t.east_m).abs());
        assert!(dir.0 > dir.1, "picked {t:?}");
        // m_k is the variance along the line of sight.
        assert!((figure_of_merit(0.0, 0.0, p, 10.0, 0.0) - 25.0).abs() < 1e-12);
        assert!((figure_of_merit(0.0, 0.0, p, 0.0, 10.0) - 1.0).abs() < 1e-12);
        assert_eq!(figure_of_merit(1.0, 1.0, p, 1.0, 1.0), 0.0);
    }

    #[test]
    fn round_robin_takes_each_in_turn() {
        let layout = Layout::new(preset("Four").expect("four")).expect("layout");
        let mut turn = 0;
        let picks: Vec<usize> = (0..6)
            .map(|_| {
                next(
                    Selection::RoundRobin,
                    &layout,
                    [0.0; 2],
                    [[1.0, 0.0], [0.0, 1.0]],
                    &mut turn,
                )
            })
            .collect();
        assert_eq!(picks, [0, 1, 2, 3, 0, 1]);
    }
}
