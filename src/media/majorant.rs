//! Majorant grids and the 3D DDA that walks a ray through them (pbrt-v4 §11.4.3,
//! `MajorantGrid` and `DDAMajorantIterator`): piecewise-constant upper bounds on σt along
//! the ray, so delta tracking takes long steps through thin regions.

use glam::{UVec3, Vec3};

use crate::color::{Channels, Rgb};
use crate::geometry::Bounds3;

/// Maximum density per cell of a regular grid over a medium's bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    /// Medium-space box the grid covers.
    pub bounds: Bounds3,
    /// Cells per axis.
    pub res: UVec3,
    values: Vec<f32>,
}

impl MajorantGrid {
    /// Builds the grid, asking `max_in(lo, hi)` for each cell's bound, with lo/hi in [0, 1]³
    /// of `bounds`.
    pub fn new(bounds: Bounds3, res: UVec3, max_in: impl Fn(Vec3, Vec3) -> f32) -> MajorantGrid {
        let mut values = Vec::with_capacity((res.x * res.y * res.z) as usize);
        let r = res.as_vec3();
        for z in 0..res.z {
            for y in 0..res.y {
                for x in 0..res.x {
                    let lo = Vec3::new(x as f32, y as f32, z as f32) / r;
                    let hi = Vec3::new((x + 1) as f32, (y + 1) as f32, (z + 1) as f32) / r;
                    values.push(max_in(lo, hi).max(0.0));
                }
            }
        }
        MajorantGrid { bounds, res, values }
    }

    #[inline]
    fn at(&self, v: [i32; 3]) -> f32 {
        self.values[((v[2] as u32 * self.res.y + v[1] as u32) * self.res.x + v[0] as u32) as usize]
    }

    /// Bytes used.
    pub fn memory_bytes(&self) -> usize {
        self.values.len() * 4
    }
}

/// A stretch of ray with a constant majorant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment<C = Rgb> {
    /// Start (ray parameter).
    pub t_min: f32,
    /// End.
    pub t_max: f32,
    /// Majorant σ over the stretch.
    pub sigma_maj: C,
}

/// Walks a ray through a [`MajorantGrid`] cell by cell.
#[derive(Clone, Debug)]
pub struct DdaIterator<'a, C = Rgb> {
    grid: &'a MajorantGrid,
    sigma_t: C,
    t_min: f32,
    t_max: f32,
    next_crossing: [f32; 3],
    delta_t: [f32; 3],
    step: [i32; 3],
    voxel_limit: [i32; 3],
    voxel: [i32; 3],
}

impl<'a, C: Channels> DdaIterator<'a, C> {
    /// Starts at `t_min` on the medium-space ray (o, d), ending at `t_max`; σmaj of a cell is
    /// `sigma_t` × the cell's value.
    pub fn new(grid: &'a MajorantGrid, o: Vec3, d: Vec3, t_min: f32, t_max: f32, sigma_t: C) -> DdaIterator<'a, C> {
        let diag = grid.bounds.max - grid.bounds.min;
        let o_grid = (o - grid.bounds.min) / diag;
        let d_grid = d / diag;
        let start = o_grid + d_grid * t_min;
        let res = grid.res.as_ivec3();
        let mut it = DdaIterator {
            grid,
            sigma_t,
            t_min,
            t_max,
            next_crossing: [0.0; 3],
            delta_t: [0.0; 3],
            step: [0; 3],
            voxel_limit: [0; 3],
            voxel: [0; 3],
        };
        for axis in 0..3 {
            let r = res[axis];
            it.voxel[axis] = ((start[axis] * r as f32) as i32).clamp(0, r - 1);
            let dir = d_grid[axis] + 0.0; // turns -0.0 into +0.0
            it.delta_t[axis] = 1.0 / (dir.abs() * r as f32);
            if dir >= 0.0 {
                let next = (it.voxel[axis] + 1) as f32 / r as f32;
                it.next_crossing[axis] = if dir == 0.0 { f32::INFINITY } else { t_min + (next - start[axis]) / dir };
                it.step[axis] = 1;
                it.voxel_limit[axis] = r;
            } else {
                let next = it.voxel[axis] as f32 / r as f32;
                it.next_crossing[axis] = t_min + (next - start[axis]) / dir;
                it.step[axis] = -1;
                it.voxel_limit[axis] = -1;
            }
        }
        it
    }
}

impl<C: Channels> Iterator for DdaIterator<'_, C> {
    type Item = Segment<C>;

    #[inline]
    fn next(&mut self) -> Option<Segment<C>> {
        if self.t_min >= self.t_max {
            return None;
        }
        let nc = &self.next_crossing;
        // The axis whose cell boundary comes first.
        let axis = if nc[0] < nc[1] {
            if nc[0] < nc[2] { 0 } else { 2 }
        } else if nc[1] < nc[2] {
            1
        } else {
            2
        };
        let t_exit = self.t_max.min(nc[axis]);
        let seg = Segment { t_min: self.t_min, t_max: t_exit, sigma_maj: self.sigma_t * self.grid.at(self.voxel) };
        self.t_min = t_exit;
        if nc[axis] > self.t_max {
            self.t_min = self.t_max;
        }
        self.voxel[axis] += self.step[axis];
        if self.voxel[axis] == self.voxel_limit[axis] {
            self.t_min = self.t_max;
        }
        self.next_crossing[axis] += self.delta_t[axis];
        Some(seg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dda_covers_the_ray_and_reports_cell_values() {
        let bounds = Bounds3::new(Vec3::ZERO, Vec3::ONE);
        let grid = MajorantGrid::new(bounds, UVec3::new(4, 1, 1), |lo, _| (lo.x * 4.0).round() + 1.0);
        let segs: Vec<Segment> =
            DdaIterator::new(&grid, Vec3::new(-1.0, 0.5, 0.5), Vec3::X, 1.0, 2.0, Rgb::ONE).collect();
        assert_eq!(segs.len(), 4);
        for (i, s) in segs.iter().enumerate() {
            assert!((s.t_min - (1.0 + i as f32 * 0.25)).abs() < 1e-6);
            assert!((s.t_max - (1.25 + i as f32 * 0.25)).abs() < 1e-6);
            assert_eq!(s.sigma_maj.x, i as f32 + 1.0);
        }
        // Backwards along a diagonal: contiguous segments that end at t_max.
        let segs: Vec<Segment> =
            DdaIterator::new(&grid, Vec3::new(2.0, 0.9, 0.2), Vec3::new(-1.0, -0.2, 0.1), 1.0, 2.0, Rgb::ONE).collect();
        assert!((segs[0].t_min - 1.0).abs() < 1e-6);
        for w in segs.windows(2) {
            assert!((w[0].t_max - w[1].t_min).abs() < 1e-6);
        }
        assert!((segs.last().unwrap().t_max - 2.0).abs() < 1e-5);
    }
}
