//! Level contours of a sampled field (marching squares), for paper 003's
//! Figs. 2-3.

/// A field sampled on a regular grid over a north/east rectangle; `None`
/// where it is undefined.
#[derive(Debug, Clone)]
pub struct Grid {
    /// South and north edges, m.
    pub north_m: (f64, f64),
    /// West and east edges, m.
    pub east_m: (f64, f64),
    /// Samples along north.
    pub rows: usize,
    /// Samples along east.
    pub cols: usize,
    /// Row-major samples, row 0 at the south edge.
    values: Vec<Option<f64>>,
}

impl Grid {
    /// Samples `f([north, east])` on `rows × cols` points (at least 2 × 2)
    /// spanning the rectangle, edges included.
    pub fn sample(
        north_m: (f64, f64),
        east_m: (f64, f64),
        rows: usize,
        cols: usize,
        f: impl Fn([f64; 2]) -> Option<f64>,
    ) -> Self {
        let (rows, cols) = (rows.max(2), cols.max(2));
        let mut values = Vec::with_capacity(rows * cols);
        for r in 0..rows {
            for c in 0..cols {
                values.push(
                    f(Self::point(north_m, east_m, rows, cols, r, c)).filter(|v| v.is_finite()),
                );
            }
        }
        Self {
            north_m,
            east_m,
            rows,
            cols,
            values,
        }
    }

    fn point(
        north_m: (f64, f64),
        east_m: (f64, f64),
        rows: usize,
        cols: usize,
        r: usize,
        c: usize,
    ) -> [f64; 2] {
        let n = north_m.0 + (north_m.1 - north_m.0) * r as f64 / (rows - 1) as f64;
        let e = east_m.0 + (east_m.1 - east_m.0) * c as f64 / (cols - 1) as f64;
        [n, e]
    }

    /// The sample at row `r`, column `c`.
    pub fn get(&self, r: usize, c: usize) -> Option<f64> {
        self.values.get(r * self.cols + c).copied().flatten()
    }

    /// `[north, east]` of row `r`, column `c`.
    pub fn at(&self, r: usize, c: usize) -> [f64; 2] {
        Self::point(self.north_m, self.east_m, self.rows, self.cols, r, c)
    }

    /// The contour at `level` as line segments `([north, east], [north,
    /// east])`: marching squares over every cell whose four corners are
    /// defined, the crossing on each edge interpolated linearly, a saddle
    /// resolved by the mean of the corners.
    pub fn contour(&self, level: f64) -> Vec<([f64; 2], [f64; 2])> {
        let mut out = Vec::new();
        for r in 0..self.rows - 1 {
            for c in 0..self.cols - 1 {
                // Corners counter-clockwise from the south-west.
                let idx = [(r, c), (r, c + 1), (r + 1, c + 1), (r + 1, c)];
                let (Some(v0), Some(v1), Some(v2), Some(v3)) = (
                    self.get(idx[0].0, idx[0].1),
                    self.get(idx[1].0, idx[1].1),
                    self.get(idx[2].0, idx[2].1),
                    self.get(idx[3].0, idx[3].1),
                ) else {
                    continue;
                };
                let v = [v0, v1, v2, v3];
                let above = v.map(|x| x >= level);
                // The crossing on edge k (corner k to corner k+1).
                let cross = |k: usize| {
                    let (a, b) = (k, (k + 1) % 4);
                    let (pa, pb) = (self.at(idx[a].0, idx[a].1), self.at(idx[b].0, idx[b].1));
                    let t = ((level - v[a]) / (v[b] - v[a])).clamp(0.0, 1.0);
                    [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])]
                };
                let edges: Vec<usize> =
                    (0..4).filter(|&k| above[k] != above[(k + 1) % 4]).collect();
                match edges.as_slice() {
                    [a, b] => out.push((cross(*a), cross(*b))),
                    [e0, e1, e2, e3] => {
                        // A saddle: pair the edges so that the centre's side
                        // (the mean) separates the corners.
                        let centre_above = v.iter().sum::<f64>() / 4.0 >= level;
                        if centre_above == above[0] {
                            out.push((cross(*e0), cross(*e1)));
                            out.push((cross(*e2), cross(*e3)));
                        } else {
                            out.push((cross(*e3), cross(*e0)));
                            out.push((cross(*e1), cross(*e2)));
                        }
                    }
                    _ => {}
                }
            }
        }
        out
    }
}
