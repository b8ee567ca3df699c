//! pbrt-v4's `rgbgrid` medium: per-voxel RGB σa, σs and Le over a box.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Affine3A, IVec3, Vec3, Vec4};
use nimbus_parser::ColorSpace;

use super::dense::{DenseGrid, trilinear};
use super::majorant::MajorantGrid;
use super::medium::MediumPoint;
use crate::color::Channels;
use crate::geometry::Bounds3;
use crate::spectra::RgbRole;

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
    /// Identifies this medium's data in the per-thread memo (an address could be reused by a
    /// later scene's medium).
    pub(super) id: u64,
}

/// The converted corner values of the cell a thread looked up last. A spectral lookup
/// evaluates 8 voxel spectra per coefficient, the larger part of a spectral `rgbgrid`
/// render; 41 % of lookups on the parity suite's smoke land in the cell before them (the
/// next tentative collision of the same ray), and reuse these. A memo is exact: the values
/// are a function of the grid, the cell and the wavelengths, all in the key.
struct CellMemo {
    /// [`RgbGridMedium::id`] of the medium the values belong to (0: none yet).
    grid: u64,
    cell: IVec3,
    lambda: Vec4,
    /// σa, σs and Le at the eight corners, as lanes.
    values: [[Vec4; 8]; 3],
}

/// The next [`RgbGridMedium::id`].
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// A new medium's id.
pub(super) fn new_id() -> u64 {
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

thread_local! {
    static MEMO: RefCell<CellMemo> = const {
        RefCell::new(CellMemo { grid: 0, cell: IVec3::ZERO, lambda: Vec4::ZERO, values: [[Vec4::ZERO; 8]; 3] })
    };
}

impl RgbGridMedium {
    /// Coefficients at world point `p`, in the path's channels: each coefficient's eight
    /// voxels around `p` converted and interpolated (pbrt-v4's `RGBGridMedium::SamplePoint`).
    #[inline]
    pub fn sample_point<C: Channels>(&self, p: Vec3, lambda: &C::Lambda) -> MediumPoint<C> {
        let pm = self.medium_from_world.transform_point3(p);
        let pu = (pm - self.bounds.min) / (self.bounds.max - self.bounds.min);
        // All grids share one resolution (one nx, ny, nz), hence one cell.
        let Some(any) = self.sigma_a.as_ref().or(self.sigma_s.as_ref()).or(self.le.as_ref()) else {
            return MediumPoint { sigma_a: C::ONE, sigma_s: C::ONE, le: C::ZERO };
        };
        let (cell, d) = any.cell(pu);
        let grids =
            [(&self.sigma_a, RgbRole::Unbounded), (&self.sigma_s, RgbRole::Unbounded), (&self.le, RgbRole::Illuminant)];
        let absent = [C::ONE, C::ONE, C::ZERO];
        let Some(key) = C::voxel_memo_key(lambda) else {
            let [sigma_a, sigma_s, le] = std::array::from_fn(|i| match grids[i].0 {
                Some(g) => trilinear(&g.corners(cell, |v| C::from_voxel(v, grids[i].1, self.space, lambda)), d),
                None => absent[i],
            });
            return MediumPoint { sigma_a, sigma_s, le: le * self.le_scale };
        };
        let id = self.id;
        MEMO.with_borrow_mut(|m| {
            if m.grid != id || m.cell != cell || m.lambda != key {
                for (values, (grid, role)) in m.values.iter_mut().zip(grids) {
                    if let Some(g) = grid {
                        *values = g.corners(cell, |v| C::from_voxel(v, role, self.space, lambda).to_lanes());
                    }
                }
                (m.grid, m.cell, m.lambda) = (id, cell, key);
            }
            let [sigma_a, sigma_s, le] = std::array::from_fn(|i| match grids[i].0 {
                Some(_) => C::from_lanes(trilinear(&m.values[i], d)),
                None => absent[i],
            });
            MediumPoint { sigma_a, sigma_s, le: le * self.le_scale }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::pack_voxel;
    use crate::media::Medium;
    use crate::media::MediumKind;
    use crate::spectra::{SampledSpectrum, SampledWavelengths};
    use glam::UVec3;

    /// A 2×2×2 spectral rgbgrid whose voxel RGBs are scaled by `k`.
    fn medium(k: f32) -> Medium {
        let space = ColorSpace::Srgb;
        let rgb = |i: usize| Vec3::new(0.1 + 0.1 * i as f32, 0.7 - 0.05 * i as f32, 0.3) * k;
        let v: Vec<Vec4> = (0..8).map(|i| pack_voxel(rgb(i), RgbRole::Unbounded, space, true)).collect();
        let le: Vec<Vec4> = (0..8).map(|i| pack_voxel(rgb(7 - i), RgbRole::Illuminant, space, true)).collect();
        let n = UVec3::splat(2);
        let grid = |v: Vec<Vec4>| DenseGrid::new(n, v);
        let bounds = Bounds3::new(Vec3::ZERO, Vec3::ONE);
        Medium::rgb_grid(
            "m".into(),
            Affine3A::IDENTITY,
            bounds,
            grid(v.clone()),
            None,
            grid(le),
            2.0,
            space,
            0.0,
            true,
            |v| v.w,
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
            sigma_s: SampledSpectrum::ONE,
            le: look(g.le.as_ref().unwrap(), RgbRole::Illuminant) * 2.0,
        }
    }

    /// The memo never returns another cell's, medium's or wavelengths' values: lookups that
    /// alternate between two media, two wavelength sets and points in one cell and in others
    /// all equal the direct evaluation.
    #[test]
    fn memoised_lookups_equal_direct_evaluation() {
        let media = [medium(1.0), medium(0.5)];
        let lambdas = [SampledWavelengths::sample_visible(0.2), SampledWavelengths::sample_visible(0.7)];
        let points = [Vec3::splat(0.3), Vec3::splat(0.4), Vec3::new(0.3, 0.3, 0.9), Vec3::new(0.8, 0.1, 0.5)];
        for round in 0..3 {
            for (i, p) in points.iter().enumerate() {
                for m in &media {
                    let lambda = &lambdas[(i + round) % 2];
                    let got = m.sample_point::<SampledSpectrum>(*p, lambda);
                    let want = direct(m, *p, lambda);
                    for (g, w) in [(got.sigma_a, want.sigma_a), (got.sigma_s, want.sigma_s), (got.le, want.le)] {
                        assert!((g - w).abs().max_element() <= 1e-6 * w.abs().max_element(), "{g} vs {w} at {p}");
                    }
                }
            }
        }
        // One medium and cell, new wavelengths (the memo is keyed by them).
        for lambda in &lambdas {
            let got = media[0].sample_point::<SampledSpectrum>(points[1], lambda);
            assert_eq!(got.sigma_a, direct(&media[0], points[1], lambda).sigma_a);
        }
        // Different media, different values (the memo is keyed by medium).
        let a = media[0].sample_point::<SampledSpectrum>(points[0], &lambdas[0]);
        let b = media[1].sample_point::<SampledSpectrum>(points[0], &lambdas[0]);
        assert_ne!(a.sigma_a, b.sigma_a);
    }
}
