//! A float voxel grid stored sparsely as 8³ bricks.
//!
//! VDB grids are sparse: a cloud's active voxels fill a small part of their bounding box. The
//! bricks here mirror VDB leaf nodes (8³ voxels at multiples of 8, values in VDB's x-major
//! order) so a reader copies a leaf into a brick as is. Bricks are found through a dense table
//! of brick indices over the active bounding box: one `u32` per 512 voxels, so a Disney-cloud
//! bounding box of ~10⁹ voxels costs ~8 MB of table, and a lookup is one shift, one table read
//! and one value read — no tree walk as in NanoVDB. Brick 0 is a brick of background values, so
//! the table's empty cells need no branch; bricks of one constant value (VDB tiles, uniform
//! leaves) are stored once and shared.
//!
//! Each brick is stored with an apron: 9³ values, its own 8³ and the first voxels of the
//! bricks above it in x, y and z. A trilinear lookup's eight corners then always sit in one
//! stored brick. Without the apron, the third of lookups whose corners straddle a brick
//! boundary ((7/8)³ do not) read each corner through the table: on the Disney cloud they
//! took 15 % of all instructions, against 12 % for every other lookup together. The apron
//! costs 1.42× the values of a non-constant brick, and the bricks just below the data, whose
//! aprons hold data, are stored too (the table reaches one brick lower on each axis for
//! them).

use std::collections::HashMap;

use glam::{Affine3A, DAffine3, DVec3, IVec3, UVec3, Vec3};

use crate::geometry::Bounds3;

/// log2 of the brick edge length.
const BRICK_LOG2: i32 = 3;
/// Voxels along a brick edge.
pub const BRICK_DIM: i32 = 1 << BRICK_LOG2;
/// Voxels in a brick.
pub const BRICK_VOXELS: usize = 1 << (3 * BRICK_LOG2);
/// Table cells beyond which a grid is refused (4 GiB of table, a 5·10¹¹-voxel box): far above
/// any real cloud, but it stops a corrupt bounding box from asking for the whole machine.
const MAX_TABLE_CELLS: u64 = 1 << 30;

/// Values stored per brick: 9³, the brick and its apron.
const PADDED_VOXELS: usize = 9 * 9 * 9;
/// Offsets, in a stored brick, of the voxels one step up in x, y and z.
const STEP_X: usize = 81;
const STEP_Y: usize = 9;

/// Offset of voxel `ijk` inside a VDB leaf (z fastest, then y, then x): the readers' order.
#[inline(always)]
fn voxel_offset(ijk: IVec3) -> usize {
    (((ijk.x & 7) << 6) | ((ijk.y & 7) << 3) | (ijk.z & 7)) as usize
}

/// Offset of voxel `ijk` inside its stored (padded) brick, in the same order.
#[inline(always)]
fn padded_offset(ijk: IVec3) -> usize {
    (ijk.x & 7) as usize * STEP_X + (ijk.y & 7) as usize * STEP_Y + (ijk.z & 7) as usize
}

/// A float voxel grid with a background value, stored as 8³ bricks, and the affine transform
/// between its index space (voxel centres at integer coordinates) and world space.
#[derive(Clone, Debug)]
pub struct SparseGrid {
    background: f32,
    /// Active voxels' bounding box, inclusive.
    index_min: IVec3,
    index_max: IVec3,
    /// The table's first brick (brick coordinates are index coordinates >> 3): one below the
    /// active box's on each axis, for the bricks whose aprons reach into it.
    brick_min: IVec3,
    /// The table's extent in bricks.
    brick_dims: UVec3,
    /// Brick number per table cell, z fastest; 0 is the background brick.
    table: Vec<u32>,
    /// `PADDED_VOXELS` values per brick.
    values: Vec<f32>,
    /// Largest value of each brick (its own 8³, not the apron), so majorants need not visit
    /// voxels.
    brick_max: Vec<f32>,
    /// Smallest value of each brick's own 8³ (for minorants).
    brick_min_value: Vec<f32>,
    world_from_index: DAffine3,
    index_from_world: DAffine3,
    /// Single-precision copies: pbrt-v4 maps points with NanoVDB's float map
    /// (`worldToIndexF`), and the renderer works in f32.
    world_from_index_f32: Affine3A,
    index_from_world_f32: Affine3A,
    world_bounds: Bounds3,
}

impl SparseGrid {
    /// A grid from dense values over the box `origin ..= origin + dims - 1`, given x fastest
    /// (`values[(z * ny + y) * nx + x]`, pbrt-v4's order for grid media); every voxel of the
    /// box counts as active, voxels outside it read `background`. The transform is the
    /// identity until [`SparseGrid::with_transform`].
    ///
    /// # Panics
    /// If a dimension is zero or `values` does not hold `nx * ny * nz` values.
    pub fn from_dense(origin: IVec3, dims: UVec3, values: &[f32], background: f32) -> SparseGrid {
        assert!(dims.min_element() > 0, "dense grid dimensions {dims} must be positive");
        let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
        assert_eq!(values.len(), nx * ny * nz, "dense grid of {dims} needs nx*ny*nz values");
        let max = origin + dims.as_ivec3() - 1;
        let mut builder = SparseGridBuilder::new(background);
        let mut brick = [background; BRICK_VOXELS];
        for bx in (origin.x >> BRICK_LOG2)..=(max.x >> BRICK_LOG2) {
            for by in (origin.y >> BRICK_LOG2)..=(max.y >> BRICK_LOG2) {
                for bz in (origin.z >> BRICK_LOG2)..=(max.z >> BRICK_LOG2) {
                    let brick_origin = IVec3::new(bx, by, bz) << BRICK_LOG2;
                    let mut mask = [0u64; 8];
                    for (n, v) in brick.iter_mut().enumerate() {
                        let ijk = brick_origin + IVec3::new((n >> 6) as i32, ((n >> 3) & 7) as i32, (n & 7) as i32);
                        let local = ijk - origin;
                        *v = if local.cmpge(IVec3::ZERO).all() && ijk.cmple(max).all() {
                            mask[n >> 6] |= 1 << (n & 63);
                            let (x, y, z) = (local.x as usize, local.y as usize, local.z as usize);
                            values[(z * ny + y) * nx + x]
                        } else {
                            background
                        };
                    }
                    builder.add_leaf(brick_origin, &brick, &mask);
                }
            }
        }
        builder.build().expect("a dense grid has active voxels and a table of its own size")
    }

    /// This grid with `world_from_index` as its transform (and world bounds recomputed).
    pub fn with_transform(mut self, world_from_index: DAffine3) -> SparseGrid {
        self.set_transform(world_from_index);
        self
    }

    /// Sets the transform; world bounds become the box of the active voxels' cells
    /// `[min, max + 1]` mapped to world space, as NanoVDB computes its world bounding box.
    pub(crate) fn set_transform(&mut self, world_from_index: DAffine3) {
        self.world_from_index = world_from_index;
        self.index_from_world = world_from_index.inverse();
        self.world_from_index_f32 =
            Affine3A::from_mat3_translation(world_from_index.matrix3.as_mat3(), world_from_index.translation.as_vec3());
        self.index_from_world_f32 = Affine3A::from_mat3_translation(
            self.index_from_world.matrix3.as_mat3(),
            self.index_from_world.translation.as_vec3(),
        );
        let lo = self.index_min.as_dvec3();
        let hi = (self.index_max + 1).as_dvec3();
        let mut bounds = Bounds3::EMPTY;
        for c in 0..8 {
            let corner = DVec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            bounds.extend(world_from_index.transform_point3(corner).as_vec3());
        }
        self.world_bounds = bounds;
    }

    /// Replaces the world bounds (a NanoVDB file stores the box pbrt-v4 uses).
    pub(crate) fn set_world_bounds(&mut self, bounds: Bounds3) {
        self.world_bounds = bounds;
    }

    /// The value of voxels that are not stored.
    pub fn background(&self) -> f32 {
        self.background
    }

    /// Bounding box of the active voxels in index space, inclusive: `(min, max)`.
    pub fn index_bounds(&self) -> (IVec3, IVec3) {
        (self.index_min, self.index_max)
    }

    /// World-space box of the active voxels' cells (`[min, max + 1]` in index space), as
    /// pbrt-v4 bounds a `nanovdb` medium.
    pub fn world_bounds(&self) -> Bounds3 {
        self.world_bounds
    }

    /// Index space to world space.
    pub fn world_from_index(&self) -> Affine3A {
        self.world_from_index_f32
    }

    /// World space to index space.
    pub fn index_from_world(&self) -> Affine3A {
        self.index_from_world_f32
    }

    /// Index space to world space in double precision, as the file stores it.
    pub fn world_from_index_f64(&self) -> DAffine3 {
        self.world_from_index
    }

    /// World space to index space in double precision.
    pub fn index_from_world_f64(&self) -> DAffine3 {
        self.index_from_world
    }

    /// Bricks stored, counting the background brick and shared constant bricks once.
    pub fn brick_count(&self) -> usize {
        self.brick_max.len()
    }

    /// Heap and inline bytes this grid occupies.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<SparseGrid>()
            + self.table.capacity() * std::mem::size_of::<u32>()
            + self.values.capacity() * std::mem::size_of::<f32>()
            + (self.brick_max.capacity() + self.brick_min_value.capacity()) * std::mem::size_of::<f32>()
    }

    /// The table cell holding brick coordinate `b`, if inside the table.
    #[inline(always)]
    fn cell(&self, brick: IVec3) -> Option<usize> {
        let b = (brick - self.brick_min).as_uvec3();
        // Negative offsets wrap to huge unsigned values, so one compare per axis suffices.
        if b.x < self.brick_dims.x && b.y < self.brick_dims.y && b.z < self.brick_dims.z {
            Some(
                ((b.x as usize * self.brick_dims.y as usize) + b.y as usize) * self.brick_dims.z as usize
                    + b.z as usize,
            )
        } else {
            None
        }
    }

    /// First value of the brick holding voxel `ijk` (the background brick outside the table).
    #[inline(always)]
    fn brick_start(&self, ijk: IVec3) -> usize {
        match self.cell(ijk >> BRICK_LOG2) {
            Some(c) => self.table[c] as usize * PADDED_VOXELS,
            None => 0,
        }
    }

    /// The value of voxel `ijk`, active or not.
    #[inline]
    pub fn value(&self, ijk: IVec3) -> f32 {
        self.values[self.brick_start(ijk) + padded_offset(ijk)]
    }

    /// Trilinear interpolation at index-space point `p`, voxel centres at integer coordinates:
    /// NanoVDB's `SampleFromVoxels<TreeT, 1>`, which pbrt-v4's `nanovdb` medium uses, with the
    /// same order of interpolation (z, then y, then x). NanoVDB writes each lerp as an fma;
    /// here it is a multiply and an add, which differs in the last bit at most and avoids a
    /// libm call on CPUs built without FMA.
    #[inline]
    pub fn sample(&self, p: Vec3) -> f32 {
        let i = crate::math::floor_ivec3(p);
        let w = p - i.as_vec3();
        // v[x][y][z] as [x * 4 + y * 2 + z]; the apron holds the upper corners, so all
        // eight are in the stored brick of `i` (the background brick beyond the table, where
        // no corner can reach data: the table reaches one brick below it).
        let o = self.brick_start(i) + padded_offset(i);
        let s = &self.values[o..o + STEP_X + STEP_Y + 2];
        let (x, y) = (STEP_X, STEP_Y);
        let v = [s[0], s[1], s[y], s[y + 1], s[x], s[x + 1], s[x + y], s[x + y + 1]];
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        lerp(
            lerp(lerp(v[0], v[1], w.z), lerp(v[2], v[3], w.z), w.y),
            lerp(lerp(v[4], v[5], w.z), lerp(v[6], v[7], w.z), w.y),
            w.x,
        )
    }

    /// Largest voxel value in the inclusive index box `min ..= max` (inactive voxels and the
    /// background included where the box reaches them); the background for an empty box.
    /// Bricks inside the box answer from their stored maxima, so a majorant grid costs a
    /// visit per brick, not per voxel.
    pub fn max_over(&self, min: IVec3, max: IVec3) -> f32 {
        self.extreme_over(min, max, &self.brick_max, f32::NEG_INFINITY, |a, b| a > b)
    }

    /// Smallest voxel value in the inclusive index box, as [`SparseGrid::max_over`] the
    /// largest (from the bricks' stored minima).
    pub fn min_over(&self, min: IVec3, max: IVec3) -> f32 {
        self.extreme_over(min, max, &self.brick_min_value, f32::INFINITY, |a, b| a < b)
    }

    /// The voxel value in `min ..= max` that no other `beats`, starting from `none`; each
    /// brick's own extreme is `per_brick[brick]`.
    fn extreme_over(
        &self,
        min: IVec3,
        max: IVec3,
        per_brick: &[f32],
        none: f32,
        beats: impl Fn(f32, f32) -> bool,
    ) -> f32 {
        if min.cmpgt(max).any() {
            return self.background;
        }
        let table_lo = self.brick_min << BRICK_LOG2;
        let table_hi = ((self.brick_min + self.brick_dims.as_ivec3()) << BRICK_LOG2) - 1;
        let lo = min.max(table_lo);
        let hi = max.min(table_hi);
        // Voxels of the box outside the table hold the background.
        let mut best = if lo != min || hi != max { self.background } else { none };
        if lo.cmpgt(hi).any() {
            return best;
        }
        for bx in (lo.x >> BRICK_LOG2)..=(hi.x >> BRICK_LOG2) {
            for by in (lo.y >> BRICK_LOG2)..=(hi.y >> BRICK_LOG2) {
                for bz in (lo.z >> BRICK_LOG2)..=(hi.z >> BRICK_LOG2) {
                    let b = IVec3::new(bx, by, bz);
                    let brick = self.table[self.cell(b).expect("brick inside the table")];
                    let stored = per_brick[brick as usize];
                    if !beats(stored, best) {
                        continue;
                    }
                    let b_lo = b << BRICK_LOG2;
                    let v_lo = lo.max(b_lo);
                    let v_hi = hi.min(b_lo + (BRICK_DIM - 1));
                    if v_lo == b_lo && v_hi == b_lo + (BRICK_DIM - 1) {
                        best = stored;
                        continue;
                    }
                    // A brick the box cuts: scan the voxels inside.
                    let start = brick as usize * PADDED_VOXELS;
                    for x in v_lo.x..=v_hi.x {
                        for y in v_lo.y..=v_hi.y {
                            for z in v_lo.z..=v_hi.z {
                                let v = self.values[start + padded_offset(IVec3::new(x, y, z))];
                                if beats(v, best) {
                                    best = v;
                                }
                            }
                        }
                    }
                }
            }
        }
        best
    }
}

/// The inclusive box of a leaf's set mask bits, in leaf coordinates. Word `x` of the mask
/// holds the slice `x` (bit `8y + z`), so the x range comes from the nonzero words and the
/// y and z ranges from the words' union: eight operations, not 512.
fn mask_bounds(active: &[u64; 8]) -> Option<(IVec3, IVec3)> {
    let x_lo = active.iter().position(|&w| w != 0)?;
    let x_hi = active.iter().rposition(|&w| w != 0)?;
    let union = active.iter().fold(0, |a, &w| a | w);
    // Byte y of the union is nonzero when row y has a set bit; OR-ing the bytes gives the z's.
    let rows = (0..8).filter(|y| (union >> (8 * y)) & 0xff != 0);
    let (y_lo, y_hi) = (rows.clone().min()?, rows.max()?);
    let columns = (0..8).fold(0u8, |a, y| a | (union >> (8 * y)) as u8);
    let (z_lo, z_hi) = (columns.trailing_zeros(), 7 - columns.leading_zeros());
    Some((IVec3::new(x_lo as i32, y_lo, z_lo as i32), IVec3::new(x_hi as i32, y_hi, z_hi as i32)))
}

/// Why a builder could not make a grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BuildIssue {
    /// No voxel or tile was active.
    NoActiveVoxels,
    /// The active bounding box needs more table cells than allowed.
    TooLarge {
        /// Cells the table would need.
        cells: u64,
    },
}

/// Collects VDB leaves and tiles, then lays them out as a [`SparseGrid`] over the bounding
/// box of the active voxels it saw (computed here, not trusted from file statistics).
pub(crate) struct SparseGridBuilder {
    background: f32,
    /// Brick pool; brick 0 is all background.
    values: Vec<f32>,
    /// Leaf bricks: (brick coordinate, pool brick).
    leaves: Vec<(IVec3, u32)>,
    /// Constant regions: (first brick, last brick inclusive, pool brick).
    tiles: Vec<(IVec3, IVec3, u32)>,
    /// Pool brick of each constant value seen, by bit pattern.
    constants: HashMap<u32, u32>,
    active_min: IVec3,
    active_max: IVec3,
}

impl SparseGridBuilder {
    /// An empty builder.
    pub(crate) fn new(background: f32) -> SparseGridBuilder {
        let mut constants = HashMap::new();
        constants.insert(background.to_bits(), 0);
        SparseGridBuilder {
            background,
            values: vec![background; BRICK_VOXELS],
            leaves: Vec::new(),
            tiles: Vec::new(),
            constants,
            active_min: IVec3::MAX,
            active_max: IVec3::MIN,
        }
    }

    /// The pool brick filled with `value`, made on first use.
    fn constant_brick(&mut self, value: f32) -> u32 {
        if let Some(&b) = self.constants.get(&value.to_bits()) {
            return b;
        }
        let b = (self.values.len() / BRICK_VOXELS) as u32;
        self.values.extend(std::iter::repeat_n(value, BRICK_VOXELS));
        self.constants.insert(value.to_bits(), b);
        b
    }

    /// Adds a leaf: `origin` a multiple of 8, `values` in VDB order (index `x*64 + y*8 + z`),
    /// `active` the 512-bit value mask (bit n in word n / 64).
    pub(crate) fn add_leaf(&mut self, origin: IVec3, values: &[f32], active: &[u64; 8]) {
        debug_assert_eq!(origin & 7, IVec3::ZERO, "leaf origin {origin} not brick aligned");
        assert_eq!(values.len(), BRICK_VOXELS, "a leaf holds 512 values");
        if let Some((lo, hi)) = mask_bounds(active) {
            self.active_min = self.active_min.min(origin + lo);
            self.active_max = self.active_max.max(origin + hi);
        }
        let first = values[0].to_bits();
        let brick = if values.iter().all(|v| v.to_bits() == first) {
            self.constant_brick(values[0])
        } else {
            let b = (self.values.len() / BRICK_VOXELS) as u32;
            self.values.extend_from_slice(values);
            b
        };
        if brick != 0 {
            self.leaves.push((origin >> BRICK_LOG2, brick));
        }
    }

    /// Adds a tile: the cube `origin .. origin + size` (size a multiple of 8) holds `value`.
    pub(crate) fn add_tile(&mut self, origin: IVec3, size: i32, value: f32, active: bool) {
        debug_assert!(size >= BRICK_DIM && size % BRICK_DIM == 0);
        if active {
            self.active_min = self.active_min.min(origin);
            self.active_max = self.active_max.max(origin + (size - 1));
        }
        if value.to_bits() == self.background.to_bits() {
            return;
        }
        let brick = self.constant_brick(value);
        let first = origin >> BRICK_LOG2;
        self.tiles.push((first, first + (size >> BRICK_LOG2) - 1, brick));
    }

    /// Lays out the grid over the active bounding box (identity transform).
    pub(crate) fn build(self) -> Result<SparseGrid, BuildIssue> {
        if self.active_min.cmpgt(self.active_max).any() {
            return Err(BuildIssue::NoActiveVoxels);
        }
        let active_lo = self.active_min >> BRICK_LOG2;
        let active_hi = self.active_max >> BRICK_LOG2;
        // One brick below the active box on each axis: those bricks' aprons reach into it.
        let brick_min = active_lo - 1;
        let dims = (active_hi.as_i64vec3() - brick_min.as_i64vec3() + 1).as_u64vec3();
        let cells = dims.x * dims.y * dims.z;
        if cells > MAX_TABLE_CELLS {
            return Err(BuildIssue::TooLarge { cells });
        }
        let brick_dims = dims.as_uvec3();
        let mut grid = SparseGrid {
            background: self.background,
            index_min: self.active_min,
            index_max: self.active_max,
            brick_min,
            brick_dims,
            table: vec![0; cells as usize],
            values: Vec::new(),
            brick_max: Vec::new(),
            brick_min_value: Vec::new(),
            world_from_index: DAffine3::IDENTITY,
            index_from_world: DAffine3::IDENTITY,
            world_from_index_f32: Affine3A::IDENTITY,
            index_from_world_f32: Affine3A::IDENTITY,
            world_bounds: Bounds3::EMPTY,
        };
        // First each cell's leaf brick in the builder's pool (8³, leaf order), over the
        // active box only: voxels beyond it read as background.
        for &(first, last, brick) in &self.tiles {
            let lo = first.max(active_lo);
            let hi = last.min(active_hi);
            for bx in lo.x..=hi.x {
                for by in lo.y..=hi.y {
                    for bz in lo.z..=hi.z {
                        let c = grid.cell(IVec3::new(bx, by, bz)).expect("clipped to the table");
                        grid.table[c] = brick;
                    }
                }
            }
        }
        for &(b, brick) in &self.leaves {
            if b.cmpge(active_lo).all() && b.cmple(active_hi).all() {
                let c = grid.cell(b).expect("inside the active box");
                grid.table[c] = brick;
            }
        }
        let leaf_of = std::mem::take(&mut grid.table);
        grid.table = vec![0; cells as usize];
        self.pad(&mut grid, &leaf_of);
        grid.set_transform(DAffine3::IDENTITY);
        Ok(grid)
    }

    /// Fills `grid`'s table and values with padded bricks made from `leaf_of`, each cell's
    /// pool brick in the 8³ layout. Only the cells whose 9³ block can hold anything but the
    /// background are visited (a brick with data and the seven below it), and bricks of
    /// equal values, constant ones included, are stored once.
    fn pad(&self, grid: &mut SparseGrid, leaf_of: &[u32]) {
        let background = self.background;
        let pool = &self.values;
        let mut table = std::mem::take(&mut grid.table);
        let dims = grid.brick_dims.as_ivec3();
        let coords = |c: usize| {
            let c = c as i32;
            IVec3::new(c / (dims.y * dims.z), (c / dims.z) % dims.y, c % dims.z)
        };
        let mut todo = vec![false; leaf_of.len()];
        for (c, _) in leaf_of.iter().enumerate().filter(|(_, b)| **b != 0) {
            let b = coords(c) + grid.brick_min;
            for d in 0..8 {
                if let Some(k) = grid.cell(b - IVec3::new(d >> 2, (d >> 1) & 1, d & 1)) {
                    todo[k] = true;
                }
            }
        }
        let leaf_value = |ijk: IVec3| match grid.cell(ijk >> BRICK_LOG2) {
            Some(c) => pool[leaf_of[c] as usize * BRICK_VOXELS + voxel_offset(ijk)],
            None => background,
        };
        let mut values = vec![background; PADDED_VOXELS];
        let (mut brick_max, mut brick_min) = (vec![background], vec![background]);
        let mut stored: HashMap<Vec<u32>, u32> = HashMap::new();
        stored.insert(vec![background.to_bits(); PADDED_VOXELS], 0);
        let mut brick = [0.0f32; PADDED_VOXELS];
        for (c, entry) in table.iter_mut().enumerate().filter(|(c, _)| todo[*c]) {
            let origin = (coords(c) + grid.brick_min) << BRICK_LOG2;
            for (n, v) in brick.iter_mut().enumerate() {
                let d = IVec3::new((n / STEP_X) as i32, ((n / STEP_Y) % 9) as i32, (n % 9) as i32);
                *v = leaf_value(origin + d);
            }
            let key: Vec<u32> = brick.iter().map(|v| v.to_bits()).collect();
            *entry = *stored.entry(key).or_insert_with(|| {
                let core = (0..BRICK_VOXELS)
                    .map(|n| brick[padded_offset(IVec3::new((n >> 6) as i32, (n >> 3) as i32, n as i32))]);
                brick_max.push(core.clone().fold(f32::NEG_INFINITY, f32::max));
                brick_min.push(core.fold(f32::INFINITY, f32::min));
                values.extend_from_slice(&brick);
                (brick_max.len() - 1) as u32
            });
        }
        values.shrink_to_fit();
        (grid.table, grid.values, grid.brick_max, grid.brick_min_value) = (table, values, brick_max, brick_min);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic test numbers (SplitMix64).
    struct Numbers(u64);
    impl Numbers {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        fn int(&mut self, lo: i32, hi: i32) -> i32 {
            lo + (self.next() % (hi - lo + 1) as u64) as i32
        }
        fn float(&mut self) -> f32 {
            (self.next() >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// A dense test grid straddling the origin, so bricks at negative coordinates are used.
    fn dense(f: impl Fn(IVec3) -> f32) -> (SparseGrid, IVec3, UVec3) {
        let origin = IVec3::new(-11, -3, 5);
        let dims = UVec3::new(21, 9, 17);
        let mut values = Vec::new();
        for z in 0..dims.z as i32 {
            for y in 0..dims.y as i32 {
                for x in 0..dims.x as i32 {
                    values.push(f(origin + IVec3::new(x, y, z)));
                }
            }
        }
        (SparseGrid::from_dense(origin, dims, &values, 0.0), origin, dims)
    }

    fn bumpy(p: IVec3) -> f32 {
        let p = p.as_vec3();
        1.0 + (0.7 * p.x).sin() * (0.3 * p.y).cos() + 0.05 * p.z
    }

    /// Trilinear interpolation written out from `value`, the reference for `sample`.
    fn reference_sample(g: &SparseGrid, p: Vec3) -> f32 {
        let i = p.floor().as_ivec3();
        let w = p - p.floor();
        let mut sum = 0.0;
        for c in 0..8 {
            let o = IVec3::new(c >> 2 & 1, c >> 1 & 1, c & 1);
            let wx = if o.x == 1 { w.x } else { 1.0 - w.x };
            let wy = if o.y == 1 { w.y } else { 1.0 - w.y };
            let wz = if o.z == 1 { w.z } else { 1.0 - w.z };
            sum += wx * wy * wz * g.value(i + o);
        }
        sum
    }

    #[test]
    fn grid_dense_values_round_trip_and_outside_is_background() {
        let (g, origin, dims) = dense(bumpy);
        let max = origin + dims.as_ivec3() - 1;
        assert_eq!(g.index_bounds(), (origin, max));
        for x in origin.x - 2..=max.x + 2 {
            for y in origin.y - 2..=max.y + 2 {
                for z in origin.z - 2..=max.z + 2 {
                    let p = IVec3::new(x, y, z);
                    let inside = p.cmpge(origin).all() && p.cmple(max).all();
                    assert_eq!(g.value(p), if inside { bumpy(p) } else { 0.0 }, "{p}");
                }
            }
        }
        assert_eq!(g.value(IVec3::splat(i32::MIN)), 0.0);
        assert_eq!(g.value(IVec3::splat(i32::MAX)), 0.0);
    }

    #[test]
    fn grid_sample_is_trilinear_with_voxel_centres_at_integers() {
        let (g, origin, _) = dense(bumpy);
        // At voxel centres the sample is the voxel.
        for p in [origin, origin + IVec3::new(7, 2, 3), IVec3::new(0, 0, 8), IVec3::new(-8, -1, 15)] {
            assert_eq!(g.sample(p.as_vec3()), g.value(p), "{p}");
        }
        // Elsewhere it matches trilinear weights, across brick edges and outside the box.
        let mut n = Numbers(7);
        for _ in 0..5000 {
            let p = Vec3::new(-14.0 + 28.0 * n.float(), -5.0 + 14.0 * n.float(), 3.0 + 22.0 * n.float());
            let (s, r) = (g.sample(p), reference_sample(&g, p));
            assert!((s - r).abs() <= 1e-5 * r.abs().max(1.0), "{p}: {s} vs {r}");
        }
        // A linear field is reproduced exactly (up to rounding) between voxel centres.
        let (lin, _, _) = dense(|p| 0.5 + 0.25 * p.x as f32 - 0.125 * p.y as f32 + 0.0625 * p.z as f32);
        let p = Vec3::new(-7.3, 0.6, 9.9);
        let expected = 0.5 + 0.25 * p.x - 0.125 * p.y + 0.0625 * p.z;
        assert!((lin.sample(p) - expected).abs() < 1e-5);
        // Non-finite points do not panic: NaN propagates, far points read the background.
        assert!(g.sample(Vec3::splat(f32::NAN)).is_nan());
        assert_eq!(g.sample(Vec3::splat(1e30)), 0.0);
    }

    #[test]
    fn grid_max_and_min_over_match_brute_force() {
        let (g, _, _) = dense(bumpy);
        let mut n = Numbers(11);
        for _ in 0..400 {
            let a = IVec3::new(n.int(-20, 15), n.int(-8, 10), n.int(0, 26));
            let b = a + IVec3::new(n.int(0, 20), n.int(0, 12), n.int(0, 14));
            let (mut max, mut min) = (f32::NEG_INFINITY, f32::INFINITY);
            for x in a.x..=b.x {
                for y in a.y..=b.y {
                    for z in a.z..=b.z {
                        max = max.max(g.value(IVec3::new(x, y, z)));
                        min = min.min(g.value(IVec3::new(x, y, z)));
                    }
                }
            }
            assert_eq!(g.max_over(a, b), max, "{a} ..= {b}");
            assert_eq!(g.min_over(a, b), min, "{a} ..= {b}");
        }
        // Empty boxes give the background.
        assert_eq!(g.max_over(IVec3::ONE, IVec3::ZERO), 0.0);
        assert_eq!(g.min_over(IVec3::ONE, IVec3::ZERO), 0.0);
    }

    #[test]
    fn grid_leaf_mask_bounds_match_the_set_bits() {
        let mut n = Numbers(3);
        for _ in 0..500 {
            let mut mask = [0u64; 8];
            for _ in 0..n.int(0, 6) {
                let bit = n.int(0, 511) as usize;
                mask[bit / 64] |= 1 << (bit % 64);
            }
            let mut expected: Option<(IVec3, IVec3)> = None;
            for bit in (0..512).filter(|&b| mask[b / 64] >> (b % 64) & 1 == 1) {
                let p = IVec3::new(bit as i32 >> 6, (bit as i32 >> 3) & 7, bit as i32 & 7);
                expected = Some(expected.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
            }
            assert_eq!(mask_bounds(&mask), expected, "{mask:x?}");
        }
    }

    #[test]
    fn grid_tiles_and_constant_leaves_share_bricks() {
        let mut b = SparseGridBuilder::new(0.0);
        let ones = [1.0f32; BRICK_VOXELS];
        let full = [u64::MAX; 8];
        b.add_leaf(IVec3::new(0, 0, 0), &ones, &full);
        b.add_leaf(IVec3::new(8, 0, 0), &ones, &full);
        b.add_tile(IVec3::new(16, 0, 0), 8, 1.0, true);
        // An inactive tile of background adds nothing; an active one extends the bounds.
        b.add_tile(IVec3::new(-128, 0, 0), 128, 0.0, true);
        let g = b.build().unwrap();
        // Ones over x 0..24, y and z 0..8, three bricks in a row. Stored with aprons, a brick is
        // known by its place along x (below the row, its first two bricks, its last) and along
        // y and z (below the row or in it), 3 × 2 × 2 kinds, plus the background brick; the
        // row's first two bricks, and the background everywhere else, are shared.
        assert_eq!(g.brick_count(), 13);
        let mut n = Numbers(3);
        for _ in 0..2000 {
            let p = Vec3::new(-12.0 + 40.0 * n.float(), -4.0 + 16.0 * n.float(), -4.0 + 16.0 * n.float());
            let (s, r) = (g.sample(p), reference_sample(&g, p));
            assert!((s - r).abs() <= 1e-6, "{p}: {s} vs {r}");
        }
        assert_eq!(g.index_bounds(), (IVec3::new(-128, 0, 0), IVec3::new(23, 127, 127)));
        assert_eq!(g.value(IVec3::new(20, 3, 3)), 1.0);
        assert_eq!(g.value(IVec3::new(-5, 3, 3)), 0.0);
        assert_eq!(g.max_over(IVec3::new(-100, 0, 0), IVec3::new(-1, 50, 50)), 0.0);
        assert_eq!(g.max_over(IVec3::new(-100, 0, 0), IVec3::new(0, 0, 0)), 1.0);
        assert_eq!(SparseGridBuilder::new(0.0).build().unwrap_err(), BuildIssue::NoActiveVoxels);
    }

    #[test]
    fn grid_a_cloud_sized_bounding_box_costs_table_not_voxels() {
        // Two leaves at opposite corners of a ~2000 × 1350 × 2450 box (6.6·10⁹ voxels, the
        // Disney cloud's extent): one u32 per brick, ~51 MB, instead of 26 GB of voxels.
        let mut b = SparseGridBuilder::new(0.0);
        let v: Vec<f32> = (0..BRICK_VOXELS).map(|i| i as f32).collect();
        b.add_leaf(IVec3::new(-992, -680, -1224), &v, &[1; 8]);
        b.add_leaf(IVec3::new(992, 664, 1216), &v, &[1 << 63; 8]);
        let g = b.build().unwrap();
        let (lo, hi) = g.index_bounds();
        let voxels = (hi - lo + 1).as_i64vec3();
        assert!(voxels.x * voxels.y * voxels.z > 6_000_000_000);
        assert!(g.memory_bytes() < 60 << 20, "{} bytes", g.memory_bytes());
        assert_eq!(g.value(IVec3::new(992, 664, 1216) + IVec3::new(0, 0, 1)), 1.0);
        assert_eq!(g.max_over(lo, hi), 511.0);
    }

    #[test]
    fn grid_transform_maps_index_to_world_and_bounds_cover_cells() {
        let (g, origin, dims) = dense(bumpy);
        let m = DAffine3::from_scale_rotation_translation(
            DVec3::splat(0.5),
            glam::DQuat::from_rotation_z(0.3),
            DVec3::new(1.0, -2.0, 3.0),
        );
        let g = g.with_transform(m);
        let p = Vec3::new(-3.25, 1.5, 9.75);
        let w = g.world_from_index().transform_point3(p);
        assert!((w.as_dvec3() - m.transform_point3(p.as_dvec3())).length() < 1e-5);
        assert!((g.index_from_world().transform_point3(w) - p).length() < 1e-4);
        let b = g.world_bounds();
        for c in [origin, origin + dims.as_ivec3()] {
            let w = m.transform_point3(c.as_dvec3()).as_vec3();
            assert!(w.cmpge(b.min - 1e-5).all() && w.cmple(b.max + 1e-5).all(), "{w} in {b:?}");
        }
    }
}
