//! Progressive multi-jittered (0,2) points with blue-noise placement ("pmj02bn"; Christensen,
//! Kensler and Kilpatrick, "Progressive Multi-Jittered Sample Sequences", 2018, Secs. 5–6).
//!
//! pbrt-v4 reads five such sequences of 65,536 points from a table generated offline. nimbus
//! generates its own with the paper's algorithm: every prefix of 2^k points is a (0,2)-net
//! in base 2 (each of the k + 1 elementary-interval shapes of area 2^-k holds one point), and
//! each point is the best of several valid candidates, the one farthest from the points
//! already placed (toroidal distance), which gives the blue-noise spectrum.

use glam::DVec2;

use crate::sampling::rng::Pcg32;

/// `count` points of a pmj02bn sequence from `seed`, each the best of `candidates` valid
/// positions, as 32-bit fixed point (`x · 2^32`), the form of pbrt-v4's tables.
pub(super) fn pmj02bn(count: usize, candidates: usize, seed: u64) -> Vec<[u32; 2]> {
    let mut b = Builder::new(count, candidates.max(1), seed);
    if count == 0 {
        return Vec::new();
    }
    let first = DVec2::new(b.uniform(), b.uniform());
    b.add(first);
    let mut n = 1;
    while n < count {
        // Points n..2n: each earlier point's diagonally opposite subquadrant (Sec. 5), which
        // keeps the prefix of 2n points stratified on the finer square-ish grid.
        b.subdivide();
        for i in 0..n.min(count - n) {
            let (cx, cy) = b.cell_of(i);
            b.place(&[(cx ^ 1, cy ^ 1)]);
        }
        if 2 * n >= count {
            break;
        }
        // Points 2n..4n: one of the two remaining subquadrants of each 2×2 block (whichever
        // gives the better candidate), then the last one diagonally opposite.
        b.subdivide();
        let mut chosen = Vec::with_capacity(n);
        for i in 0..n.min(count - 2 * n) {
            let (cx, cy) = b.cell_of(i);
            chosen.push(b.place(&[(cx ^ 1, cy), (cx, cy ^ 1)]));
        }
        for &(cx, cy) in chosen.iter().take(count.saturating_sub(3 * n)) {
            b.place(&[(cx ^ 1, cy ^ 1)]);
        }
        n *= 4;
    }
    b.points.iter().map(|p| [fixed(p.x), fixed(p.y)]).collect()
}

/// `x ∈ [0, 1)` as 32-bit fixed point: `floor(x · 2^k)` is the top `k` bits for every `k`.
fn fixed(x: f64) -> u32 {
    (x * 4_294_967_296.0) as u32
}

struct Builder {
    points: Vec<DVec2>,
    /// log2 of the point count the current pass fills up to: every elementary shape has
    /// 2^log_n strata.
    log_n: u32,
    /// Cells per side of the placement grid (2^ceil(log_n / 2)).
    dim: usize,
    /// `occupied[a]`: the strata of the shape with 2^a columns and 2^(log_n − a) rows.
    occupied: Vec<Vec<bool>>,
    /// Index + 1 of the point in each placement cell (at most one), 0 when empty: the
    /// nearest-neighbour search walks rings of cells.
    grid: Vec<u32>,
    rng: Pcg32,
    candidates: usize,
    /// Free columns of one cell and valid rows of one column, reused.
    free: Vec<usize>,
    rows: Vec<usize>,
}

impl Builder {
    fn new(count: usize, candidates: usize, seed: u64) -> Builder {
        Builder {
            points: Vec::with_capacity(count),
            log_n: 0,
            dim: 1,
            occupied: vec![vec![false]],
            grid: vec![0],
            rng: Pcg32::new(seed, 0x0070_6d6a_3032_626e),
            candidates,
            free: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// Uniform in [0, 1) with 53 bits.
    fn uniform(&mut self) -> f64 {
        let bits = (u64::from(self.rng.next_u32()) << 21) ^ u64::from(self.rng.next_u32() >> 11);
        bits as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    /// Uniform integer in 0..n.
    fn below(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n - 1)
    }

    /// Doubles the strata of every shape (and, at odd powers of two, the placement grid),
    /// then re-registers the points already placed.
    fn subdivide(&mut self) {
        self.log_n += 1;
        if self.log_n % 2 == 1 {
            self.dim *= 2;
        }
        let strata = 1usize << self.log_n;
        self.occupied = vec![vec![false; strata]; self.log_n as usize + 1];
        self.grid = vec![0; self.dim * self.dim];
        for i in 0..self.points.len() {
            self.register(i);
        }
    }

    fn cell_of(&self, i: usize) -> (usize, usize) {
        let p = self.points[i];
        ((p.x * self.dim as f64) as usize, (p.y * self.dim as f64) as usize)
    }

    fn stratum(&self, a: usize, p: DVec2) -> usize {
        let cols = 1usize << a;
        let rows = 1usize << (self.log_n as usize - a);
        (p.y * rows as f64) as usize * cols + (p.x * cols as f64) as usize
    }

    fn register(&mut self, i: usize) {
        let p = self.points[i];
        for a in 0..self.occupied.len() {
            let s = self.stratum(a, p);
            self.occupied[a][s] = true;
        }
        let (cx, cy) = self.cell_of(i);
        self.grid[cy * self.dim + cx] = i as u32 + 1;
    }

    fn add(&mut self, p: DVec2) {
        self.points.push(p);
        self.register(self.points.len() - 1);
    }

    /// A position in cell (cx, cy) of the placement grid whose every elementary interval is
    /// still empty, or `None` when the cell has none; `free` holds cx's free columns
    /// ([`Builder::collect_free`]).
    ///
    /// In strata of the finest level (2^log_n columns and rows), a point in column `x` and row
    /// `y` lies in the stratum `(y >> a, x >> (log_n − a))` of the shape with 2^a columns.
    /// Fixing y's bits from the top, the j-th bit completes the row of the shape with 2^j
    /// rows, so a depth-first walk over y's bits prunes as soon as a shape is occupied
    /// (Pharr's observation in "Efficient generation of points that satisfy two-dimensional
    /// elementary intervals", JCGT 2019). The column is drawn first among the cell's free
    /// ones, then the row among the valid ones for it.
    fn candidate(&mut self, cy: usize) -> Option<DVec2> {
        let k = self.log_n as usize;
        let strata = 1usize << k;
        let cell_bits = self.dim.trailing_zeros() as usize;
        while !self.free.is_empty() {
            let pick = self.below(self.free.len());
            let x = self.free[pick];
            // The rows above the cell's own bits are fixed by cy.
            let fixed_ok = (1..=cell_bits).all(|j| {
                let prefix = cy >> (cell_bits - j);
                !self.occupied[k - j][(prefix << (k - j)) | (x >> j)]
            });
            self.rows.clear();
            if fixed_ok {
                self.valid_rows(x, cy, cell_bits);
            }
            if self.rows.is_empty() {
                // No row fits this column: never draw it again for this cell.
                self.free.swap_remove(pick);
                continue;
            }
            let pick = self.below(self.rows.len());
            let y = self.rows[pick];
            let (u, v) = (self.uniform(), self.uniform());
            return Some(DVec2::new((x as f64 + u) / strata as f64, (y as f64 + v) / strata as f64));
        }
        None
    }

    /// Makes `free` the columns of cell column `cx` whose 1D stratum is empty.
    fn collect_free(&mut self, cx: usize) {
        let k = self.log_n as usize;
        let per_cell = (1usize << k) >> self.dim.trailing_zeros();
        self.free.clear();
        self.free.extend((cx * per_cell..(cx + 1) * per_cell).filter(|&x| !self.occupied[k][x]));
    }

    /// Pushes onto `rows` every full row whose top `j` bits are `prefix` and whose every
    /// shape's stratum is free for column `x`.
    fn valid_rows(&mut self, x: usize, prefix: usize, j: usize) {
        let k = self.log_n as usize;
        if j == k {
            self.rows.push(prefix);
            return;
        }
        for bit in 0..2 {
            let p = (prefix << 1) | bit;
            if !self.occupied[k - j - 1][(p << (k - j - 1)) | (x >> (j + 1))] {
                self.valid_rows(x, p, j + 1);
            }
        }
    }

    /// Adds the best of `candidates` valid positions in each of `cells`: the one farthest from
    /// its nearest neighbour (best-candidate sampling, Sec. 6). Returns the cell it went to.
    ///
    /// A valid position is unique up to its finest stratum (a (0,2)-net of n points leaves
    /// exactly one valid stratum of the 2n-point net per cell), so the jitter inside it is
    /// the only freedom within a cell; the choice between the two subquadrants of the second
    /// half of each pass is where best-candidate placement shapes the spectrum.
    fn place(&mut self, cells: &[(usize, usize)]) -> (usize, usize) {
        let mut best = None;
        let mut best_d2 = -1.0;
        for &(cx, cy) in cells {
            self.collect_free(cx);
            for _ in 0..self.candidates {
                let Some(p) = self.candidate(cy) else { break };
                let d2 = self.nearest_distance2(p, best_d2);
                if d2 > best_d2 {
                    best_d2 = d2;
                    best = Some((p, (cx, cy)));
                }
            }
        }
        // Without a valid position (never seen: the tests check every prefix) the point
        // still lands in the first cell, so the sequence stays well spread.
        let (p, cell) = best.unwrap_or_else(|| {
            let (cx, cy) = cells[0];
            let s = 1.0 / self.dim as f64;
            (DVec2::new((cx as f64 + self.uniform()) * s, (cy as f64 + self.uniform()) * s), (cx, cy))
        });
        self.add(p);
        cell
    }

    /// Squared toroidal distance from `p` to the nearest placed point, searched ring by ring
    /// over the placement grid; stops early once the nearest is known to be closer than
    /// `enough` (a candidate that cannot win).
    fn nearest_distance2(&self, p: DVec2, enough: f64) -> f64 {
        let dim = self.dim as isize;
        let cell = 1.0 / self.dim as f64;
        let (px, py) = ((p.x * self.dim as f64) as isize, (p.y * self.dim as f64) as isize);
        let mut best = f64::INFINITY;
        let visit = |x: isize, y: isize, best: &mut f64| {
            let i = self.grid[(y.rem_euclid(dim) * dim + x.rem_euclid(dim)) as usize];
            if i > 0 {
                let q = self.points[i as usize - 1];
                let dx = (q.x - p.x).abs();
                let dy = (q.y - p.y).abs();
                let (dx, dy) = (dx.min(1.0 - dx), dy.min(1.0 - dy));
                *best = best.min(dx * dx + dy * dy);
            }
        };
        visit(px, py, &mut best);
        for r in 1..=dim / 2 + 1 {
            for x in px - r..=px + r {
                visit(x, py - r, &mut best);
                visit(x, py + r, &mut best);
            }
            for y in py - r + 1..py + r {
                visit(px - r, y, &mut best);
                visit(px + r, y, &mut best);
            }
            // Every point outside the rings searched is at least r cells away.
            let reach = r as f64 * cell;
            if best <= reach * reach || best < enough {
                break;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `points` put exactly one point in every elementary interval of area 1/len
    /// (len a power of two): the (0,2)-net property.
    fn is_02_net(points: &[[u32; 2]]) -> bool {
        let k = points.len().trailing_zeros();
        (0..=k).all(|a| {
            let mut seen = vec![false; points.len()];
            points.iter().all(|p| {
                let col = if a == 0 { 0 } else { (p[0] >> (32 - a)) as usize };
                let row = if a == k { 0 } else { (p[1] >> (32 - (k - a))) as usize };
                !std::mem::replace(&mut seen[(row << a) | col], true)
            })
        })
    }

    #[test]
    fn every_power_of_two_prefix_is_a_02_net() {
        let points = pmj02bn(4096, 10, 3);
        assert_eq!(points.len(), 4096);
        for k in 0..=12 {
            assert!(is_02_net(&points[..1 << k]), "prefix of {} points", 1 << k);
        }
    }

    #[test]
    fn prefixes_do_not_depend_on_the_count() {
        let long = pmj02bn(1024, 10, 9);
        assert_eq!(pmj02bn(100, 10, 9), long[..100]);
        assert_ne!(pmj02bn(100, 10, 10), long[..100]);
    }

    /// The smallest toroidal distance between any two of `points`.
    fn min_distance(points: &[[u32; 2]]) -> f64 {
        let p: Vec<DVec2> = points.iter().map(|p| DVec2::new(p[0] as f64, p[1] as f64) / 4_294_967_296.0).collect();
        let mut best = f64::INFINITY;
        for i in 0..p.len() {
            for j in 0..i {
                let d = (p[i] - p[j]).abs();
                let d = d.min(DVec2::ONE - d);
                best = best.min(d.length());
            }
        }
        best
    }

    #[test]
    fn best_candidates_spread_the_points() {
        // Best-candidate placement keeps close pairs apart where it has room to: the closest
        // pair of 256 points, averaged over 8 seeds, in units of the spacing 1/√N, is 0.15
        // for plain pmj02 (one candidate, random subquadrants) and 0.24 with ten.
        let n = 256;
        let mean = |candidates| (0..8).map(|s| min_distance(&pmj02bn(n, candidates, s))).sum::<f64>() / 8.0 * 16.0;
        let (plain, blue) = (mean(1), mean(10));
        assert!(blue > 1.3 * plain, "closest pair {blue:.3} vs {plain:.3} spacings");
    }
}
