//! pbrt-v4's `rgbgrid` medium: per-voxel RGB σa, σs and Le over a box.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Affine3A, IVec3, Vec3, Vec4};
use nimbus_parser::ColorSpace;

use super::dense::{DenseGrid, trilinear};
use super::majorant::{Bands, MajorantGrid};
use super::medium::MediumPoint;
use crate::channels::Channels;
use crate::geometry::Bounds3;
use crate::spectra::{RgbRole, SigmoidPolynomial};

/// Per-voxel RGB coefficients (pbrt-v4's `rgbgrid`). Each voxel's spectrum is four floats:
/// for RGB transport its film RGB (and a spare lane), for spectral transport the sigmoid
/// polynomial and scale of its RGB spectrum, fitted once at build time, so a lookup evaluates
/// the eight voxels around the point at the path's wavelengths and interpolates, as pbrt-v4's
/// `SampledGrid` of RGB spectra does.
#[derive(Clone, Debug)]
pub struct RgbGridMedium {
    /// Medium-from-world transform.
    pub medium_from_world: Affine3A,
    /// The box the grids cover.
    pub bounds: Bounds3,
    /// σa per voxel (scale applied), or 1 everywhere when absent.
    pub sigma_a: Option<DenseGrid<Vec4>>,
    /// σs per voxel (scale applied), or 1 everywhere when absent.
    pub sigma_s: Option<DenseGrid<Vec4>>,
    /// Le per voxel (an illuminant spectrum for spectral transport).
    pub le: Option<DenseGrid<Vec4>>,
    /// Multiplier on `le`.
    pub le_scale: f32,
    /// Color space of the voxels' RGB.
    pub space: ColorSpace,
    /// Majorant grid (of max σt over channels).
    pub majorant: MajorantGrid,
    /// [0, 1]³-of-`bounds`-from-world transform (the grids' lookup coordinates).
    pub(super) unit_from_world: Affine3A,
    /// Identifies this medium's data in the per-thread memo (an address could be reused by a
    /// later scene's medium).
    pub(super) id: u64,
}

/// A thread's converted voxel values. A spectral lookup converts 8 voxel spectra per
/// coefficient at the path's wavelengths, the larger part of a spectral `rgbgrid` render, and
/// a path comes back to the same voxels: 41 % of lookups on the parity suite's smoke land in
/// the cell before them (the next tentative collision of the same ray), and about two thirds
/// of the other lookups' corners were converted before on the same path (by its earlier
/// collisions and its shadow rays through the same cells). So the last cell's corners are
/// kept, and every voxel converted for the current medium and wavelengths sits in a
/// direct-mapped cache (6 % of the smoke's render time saved). Both are exact: the values are
/// a function of the medium, the voxel and the wavelengths, all in the keys.
struct Memo<const N: usize> {
    /// [`RgbGridMedium::id`] of the medium the values belong to (0: none yet).
    grid: u64,
    /// The wavelengths they were converted at.
    lambda: Vec4,
    /// The cell of `corners`.
    cell: IVec3,
    /// σa, σs (and Le) at each of the eight corners of `cell`: one corner's values side by
    /// side, so a cached voxel is one copy and the interpolation weighs them all at once.
    corners: [Coefficients<N>; 8],
    /// Generation of (`grid`, `lambda`): a cache slot is valid while its tag holds it.
    stamp: u32,
    /// The voxel cache, allocated on a thread's first spectral lookup.
    cache: Option<Box<VoxelCache<N>>>,
}

/// Slots of the voxel cache (48 KiB of values per thread); a path converts a few dozen voxels.
const SLOTS: usize = 1 << CACHE_BITS;
const CACHE_BITS: u32 = 10;

/// A direct-mapped cache of converted voxels. Fixed-size arrays: a slot index is provably in
/// range, so the lookups carry no bounds checks.
struct VoxelCache<const N: usize> {
    /// Per slot, the stamp (high half) and voxel index (low half) its values belong to.
    tags: [u64; SLOTS],
    /// Per slot, σa, σs (and Le) of its voxel.
    slots: [Coefficients<N>; SLOTS],
}

/// σa, σs (and Le, for N = 3) of one voxel or point, as lanes; interpolated lane by lane with
/// the arithmetic of [`trilinear`] on each (so the result is the same, bit for bit). A medium
/// without an Le grid (most) keeps two, and interpolates no zeros.
#[derive(Clone, Copy)]
struct Coefficients<const N: usize>([Vec4; N]);

impl<const N: usize> std::ops::Add for Coefficients<N> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Coefficients(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
}

impl<const N: usize> std::ops::Mul<f32> for Coefficients<N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, t: f32) -> Self {
        Coefficients(std::array::from_fn(|i| self.0[i] * t))
    }
}

impl<const N: usize> Memo<N> {
    const EMPTY: Memo<N> = Memo {
        grid: 0,
        lambda: Vec4::ZERO,
        cell: IVec3::ZERO,
        corners: [Coefficients([Vec4::ZERO; N]); 8],
        stamp: 0,
        cache: None,
    };

    /// The slot of voxel `i`: Fibonacci hashing, since plain low bits would put the z and
    /// z + 1 corners of a grid whose x·y size is a multiple of the cache into one slot.
    #[inline]
    fn slot(i: usize) -> usize {
        ((i as u32).wrapping_mul(0x9e37_79b9) >> (32 - CACHE_BITS)) as usize
    }
}

/// The largest value in band `b` of `bands` of a voxel packed for spectral transport or not:
/// its RGB channel `b`, or its largest value over all channels (for spectral transport, the
/// maximum of its spectrum, which can exceed every RGB component).
pub(super) fn band_max(v: Vec4, spectral: bool, bands: Bands, b: usize) -> f32 {
    match (spectral, bands) {
        (false, Bands::Rgb) => v[b],
        (false, Bands::Gray) => v.truncate().max_element(),
        // An empty voxel's polynomial may be anything; it is zero.
        (true, _) if v.w == 0.0 => 0.0,
        (true, _) => SigmoidPolynomial { c0: v.x, c1: v.y, c2: v.z }.max_value() * v.w,
    }
}

/// The next [`RgbGridMedium::id`].
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// A new medium's id.
pub(super) fn new_id() -> u64 {
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

thread_local! {
    /// The memo of media without an Le grid (σa and σs per voxel).
    static MEMO_2: RefCell<Memo<2>> = const { RefCell::new(Memo::<2>::EMPTY) };
    /// The memo of media with one (σa, σs and Le).
    static MEMO_3: RefCell<Memo<3>> = const { RefCell::new(Memo::<3>::EMPTY) };
}

impl RgbGridMedium {
    /// Coefficients at world point `p`, in the path's channels: each coefficient's eight
    /// voxels around `p` converted and interpolated (pbrt-v4's `RGBGridMedium::SamplePoint`).
    #[inline]
    pub fn sample_point<C: Channels>(&self, p: Vec3, lambda: &C::Lambda) -> MediumPoint<C> {
        let pu = self.unit_from_world.transform_point3(p);
        // All grids share one resolution (one nx, ny, nz), hence one cell.
        let Some(any) = self.sigma_a.as_ref().or(self.sigma_s.as_ref()).or(self.le.as_ref()) else {
            return MediumPoint { sigma_a: C::ONE, sigma_s: C::ONE, le: C::ZERO };
        };
        let (cell, d) = any.cell(pu);
        let grids = [
            self.sigma_a.as_ref().map(|g| (g, RgbRole::Unbounded)),
            self.sigma_s.as_ref().map(|g| (g, RgbRole::Unbounded)),
            self.le.as_ref().map(|g| (g, RgbRole::Illuminant)),
        ];
        let absent = [C::ONE, C::ONE, C::ZERO];
        let [sigma_a, sigma_s, le] = match C::voxel_memo_key(lambda) {
            None => std::array::from_fn(|i| match grids[i] {
                Some((g, role)) => trilinear(&g.corners(cell, |v| C::from_voxel(v, role, self.space, lambda)), d),
                None => absent[i],
            }),
            Some(key) => {
                let lanes = if grids[2].is_some() {
                    self.memoised::<C, 3>(&MEMO_3, key, any, cell, d, grids, lambda)
                } else {
                    let [a, s] = self.memoised::<C, 2>(&MEMO_2, key, any, cell, d, [grids[0], grids[1]], lambda);
                    [a, s, Vec4::ZERO]
                };
                std::array::from_fn(|i| if grids[i].is_some() { C::from_lanes(lanes[i]) } else { absent[i] })
            }
        };
        MediumPoint { sigma_a, sigma_s, le: le * self.le_scale }
    }

    /// The first N coefficients' values at the point in `cell` at `d`, as lanes (absent grids'
    /// lanes meaningless), through `memo` (converted at `key`, the wavelengths of `lambda`).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn memoised<C: Channels, const N: usize>(
        &self,
        memo: &'static std::thread::LocalKey<RefCell<Memo<N>>>,
        key: Vec4,
        any: &DenseGrid<Vec4>,
        cell: IVec3,
        d: Vec3,
        grids: [Option<(&DenseGrid<Vec4>, RgbRole)>; N],
        lambda: &C::Lambda,
    ) -> [Vec4; N] {
        let id = self.id;
        // Converts voxel `v` of each present grid (`v` must be a voxel of the grids).
        let convert = |v: usize| {
            Coefficients(std::array::from_fn(|i| match grids[i] {
                // SAFETY: the grids share one resolution (`Medium::rgb_grid` asserts it), and `v` is
                // one of their voxels (`corner_indices` gives only those).
                Some((g, role)) => {
                    C::from_voxel(unsafe { *g.values().get_unchecked(v) }, role, self.space, lambda).to_lanes()
                }
                None => Vec4::ZERO,
            }))
        };
        memo.with_borrow_mut(|m| {
            if m.grid != id || m.lambda != key {
                // Other wavelengths or another medium: every slot is stale.
                (m.grid, m.lambda, m.cell) = (id, key, IVec3::MIN);
                m.stamp = m.stamp.wrapping_add(1);
                if m.stamp == 0 || m.cache.is_none() {
                    let cache = m.cache.get_or_insert_with(|| {
                        Box::new(VoxelCache { tags: [0; SLOTS], slots: [Coefficients([Vec4::ZERO; N]); SLOTS] })
                    });
                    cache.tags = [u64::MAX; SLOTS];
                    m.stamp = 1;
                }
            }
            if m.cell != cell {
                m.cell = cell;
                match any.corner_indices(cell) {
                    Some(corners) => {
                        let cache = m.cache.as_mut().expect("allocated with the stamp");
                        for (k, &v) in corners.iter().enumerate() {
                            let slot = Memo::<N>::slot(v);
                            let tag = (m.stamp as u64) << 32 | v as u64;
                            if cache.tags[slot] != tag {
                                cache.tags[slot] = tag;
                                cache.slots[slot] = convert(v);
                            }
                            m.corners[k] = cache.slots[slot];
                        }
                    }
                    // A cell on the grid's edge: its outer corners are zero, not voxels.
                    None => {
                        for (i, grid) in grids.iter().enumerate() {
                            if let Some((g, role)) = grid {
                                let c = g.corners(cell, |v| C::from_voxel(v, *role, self.space, lambda).to_lanes());
                                for (corner, value) in m.corners.iter_mut().zip(c) {
                                    corner.0[i] = value;
                                }
                            }
                        }
                    }
                }
            }
            trilinear(&m.corners, d).0
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channels::pack_voxel;
    use crate::media::Medium;
    use crate::media::MediumKind;
    use crate::spectra::{SampledSpectrum, SampledWavelengths};
    use glam::UVec3;

    /// A 40×6×5 rgbgrid (some voxels empty, as in a smoke) of pseudo-random
    /// colours scaled by `k`, with σa, σs and Le, packed for spectral transport or RGB.
    fn medium(k: f32, spectral: bool) -> Medium {
        let space = ColorSpace::Srgb;
        let n = UVec3::new(40, 6, 5);
        let count = (n.x * n.y * n.z) as usize;
        let mut state = 0x2545_f491_u32;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state % 10_000) as f32 / 10_000.0
        };
        let mut voxels = |role| -> Vec<Vec4> {
            (0..count)
                .map(|i| {
                    // Some empty voxels, as in a smoke.
                    let rgb = if i % 7 == 3 { Vec3::ZERO } else { Vec3::new(rnd(), rnd(), rnd()) * k };
                    pack_voxel(rgb, role, space, spectral)
                })
                .collect()
        };
        let (sa, ss, le) = (voxels(RgbRole::Unbounded), voxels(RgbRole::Unbounded), voxels(RgbRole::Illuminant));
        let grid = |v: Vec<Vec4>| DenseGrid::new(n, v);
        let bounds = Bounds3::new(Vec3::ZERO, Vec3::ONE);
        Medium::rgb_grid(
            "m".into(),
            Affine3A::IDENTITY,
            bounds,
            grid(sa),
            grid(ss),
            grid(le),
            2.0,
            space,
            0.0,
            true,
            spectral,
        )
    }

    /// pbrt-v4's lookup written out: each voxel's spectrum at the wavelengths, interpolated.
    fn direct(m: &Medium, p: Vec3, lambda: &SampledWavelengths) -> MediumPoint<SampledSpectrum> {
        let MediumKind::RgbGrid(g) = &m.kind else { unreachable!() };
        let look = |grid: &DenseGrid<Vec4>, role| {
            grid.lookup_map(p, |v| SampledSpectrum::from_voxel(v, role, ColorSpace::Srgb, lambda))
        };
        MediumPoint {
            sigma_a: look(g.sigma_a.as_ref().unwrap(), RgbRole::Unbounded),
            sigma_s: look(g.sigma_s.as_ref().unwrap(), RgbRole::Unbounded),
            le: g.le.as_ref().map_or(SampledSpectrum::ZERO, |le| look(le, RgbRole::Illuminant) * 2.0),
        }
    }

    /// The memo never returns another cell's, medium's or wavelengths' values:
    /// lookups that walk through neighbouring cells, jump, come back, and alternate between
    /// three media (one without an Le grid, memoised apart) and two wavelength sets all equal
    /// the direct evaluation.
    #[test]
    fn memoised_lookups_equal_direct_evaluation() {
        let mut no_le = medium(0.8, true);
        if let MediumKind::RgbGrid(g) = &mut no_le.kind {
            g.le = None;
        }
        let media = [medium(1.0, true), medium(0.5, true), no_le];
        let lambdas = [SampledWavelengths::sample_visible(0.2), SampledWavelengths::sample_visible(0.7)];
        let check = |m: &Medium, p: Vec3, lambda: &SampledWavelengths| {
            let got = m.sample_point::<SampledSpectrum>(p, lambda);
            let want = direct(m, p, lambda);
            for (g, w) in [(got.sigma_a, want.sigma_a), (got.sigma_s, want.sigma_s), (got.le, want.le)] {
                assert!((g - w).abs().max_element() <= 1e-6 * w.abs().max_element().max(1e-3), "{g} vs {w} at {p}");
            }
        };
        for round in 0..12 {
            // A ray's tentative collisions: same cell, the next cell, a few cells on, past the
            // edge; then the same walk with another medium or the other wavelengths.
            let lambda = &lambdas[round % 2];
            let m = &media[round / 2 % 3];
            let (o, d) = (Vec3::new(-0.01, 0.13 + 0.1 * round as f32, 0.31), Vec3::new(1.0, 0.37, 0.21).normalize());
            for t in [0.0, 0.004, 0.01, 0.02, 0.045, 0.046, 0.3, 0.31, 0.305, 0.9, 0.02, 1.2] {
                check(m, o + d * t, lambda);
            }
            // Every voxel of the grid, twice: slots are reused by other voxels in between.
            for pass in 0..2 {
                for i in 0..40 * 6 * 5 {
                    let v = Vec3::new((i % 40) as f32, (i / 40 % 6) as f32, (i / 240) as f32);
                    let p = (v + 0.3 + 0.2 * pass as f32) / Vec3::new(40.0, 6.0, 5.0);
                    check(m, p, lambda);
                }
            }
        }
        // Different media, different values (the memo is keyed by medium).
        let p = Vec3::splat(0.4);
        let a = media[0].sample_point::<SampledSpectrum>(p, &lambdas[0]);
        let b = media[1].sample_point::<SampledSpectrum>(p, &lambdas[0]);
        assert_ne!(a.sigma_a, b.sigma_a);
    }

    /// Walks 400 rays through `m` in channels `C` (wavelengths from `lambda_of` the ray's
    /// index), checking σt ≤ σmaj at 16 points of every segment; returns how close σt came to
    /// its bound and whether the bound differed between channels somewhere.
    fn walk<C: Channels + std::fmt::Display>(m: &Medium, lambda_of: impl Fn(usize) -> C::Lambda) -> (f32, bool) {
        use crate::geometry::Ray;
        let (mut tightness, mut colored) = (0.0f32, false);
        for k in 0..400 {
            let o = Vec3::new(-0.5, (k % 20) as f32 / 20.0, (k / 20) as f32 / 20.0);
            let d = Vec3::new(1.0, 0.3 * ((k % 7) as f32 - 3.0) / 3.0, 0.2).normalize();
            let (ray, lambda) = (Ray::new(o, d), lambda_of(k));
            for seg in m.segments::<C>(&ray, 10.0, &lambda) {
                let lanes = seg.sigma_maj.to_lanes();
                let used = &lanes.to_array()[..C::CHANNELS];
                let (lo, hi) = used.iter().fold((f32::MAX, 0.0f32), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
                colored |= hi > 1.2 * lo;
                for j in 0..16 {
                    let t = seg.t_min + (seg.t_max - seg.t_min) * (j as f32 + 0.5) / 16.0;
                    let mp = m.sample_point::<C>(ray.at(t), &lambda);
                    let st = (mp.sigma_a + mp.sigma_s).to_lanes();
                    for c in 0..C::CHANNELS {
                        assert!(
                            st[c] <= lanes[c] * 1.0001,
                            "channel {c}: {} > {}",
                            mp.sigma_a + mp.sigma_s,
                            seg.sigma_maj
                        );
                        tightness = tightness.max(st[c] / lanes[c]);
                    }
                }
            }
        }
        (tightness, colored)
    }

    /// The majorant grid bounds σt at every point of every segment, per channel in RGB
    /// transport and over the spectrum in spectral transport; not vacuously (σt comes near
    /// its bound somewhere).
    #[test]
    fn majorants_bound_sigma_t_in_every_channel() {
        use crate::color::Rgb;
        let spectral = walk::<SampledSpectrum>(&medium(1.0, true), |k| {
            SampledWavelengths::sample_visible((k as f32 * 0.618_034).fract())
        });
        assert!(spectral.0 > 0.8, "σt at most {} of σmaj", spectral.0);
        let (tightness, colored) = walk::<Rgb>(&medium(1.0, false), |_| ());
        assert!(tightness > 0.8, "σt at most {tightness} of σmaj");
        assert!(colored, "RGB majorants are per channel");
    }
}
