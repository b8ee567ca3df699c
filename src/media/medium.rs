//! Media at render time: coefficients at points, and majorant segments along rays. Each
//! medium stores what it needs: a homogeneous medium no grid, a density grid one float
//! channel, an `rgbgrid` three.

use glam::{Affine3A, UVec3, Vec3, Vec4};

use super::cloud::Cloud;
use super::dense::DenseGrid;
use super::grid::SparseGrid;
use super::majorant::{Bands, DdaIterator, MajorantGrid, Segment};
use super::rgbgrid::RgbGridMedium;
use nimbus_parser::ColorSpace;

use crate::channels::Channels;
use crate::color::Rgb;
use crate::geometry::{Bounds3, Ray};
use crate::spectra::{BlackbodyRgbTable, SpectrumValue};

/// Scattering properties at a point, in the path's channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumPoint<C = Rgb> {
    /// Absorption coefficient.
    pub sigma_a: C,
    /// Scattering coefficient.
    pub sigma_s: C,
    /// Emitted radiance (emission is σa·Le).
    pub le: C,
}

/// Voxel data of a medium: dense over its box, or sparse with its own index transform.
#[derive(Clone, Debug)]
pub enum Field {
    /// `uniformgrid`: a dense grid over the medium's box (looked up in [0, 1]³).
    Dense(DenseGrid<f32>),
    /// `nanovdb`/`vdb`: a sparse grid, looked up through its index-from-medium transform.
    Sparse(Box<SparseGrid>),
}

impl Field {
    /// The value at medium-space point `pm`, whose position in the box is `pu` ∈ [0, 1]³.
    #[inline]
    pub fn at(&self, pm: Vec3, pu: Vec3) -> f32 {
        match self {
            Field::Dense(g) => g.lookup(pu),
            Field::Sparse(g) => g.sample(g.index_from_world().transform_point3(pm)),
        }
    }

    fn memory_bytes(&self) -> usize {
        match self {
            Field::Dense(g) => g.memory_bytes(),
            Field::Sparse(g) => g.memory_bytes(),
        }
    }
}

/// Where a heterogeneous medium's density comes from.
#[derive(Clone, Debug)]
pub enum Density {
    /// Voxel data.
    Field(Field),
    /// `cloud`: pbrt-v4's procedural cloud.
    Cloud(Cloud),
}

impl Density {
    #[inline]
    fn at(&self, pm: Vec3, pu: Vec3) -> f32 {
        match self {
            Density::Field(f) => f.at(pm, pu),
            // pbrt-v4 evaluates its cloud at the medium-space point itself; the bounds only
            // clip rays (with p0, p1 other than the unit box the cloud is not rescaled).
            Density::Cloud(c) => c.density_at(pm),
        }
    }

    fn memory_bytes(&self) -> usize {
        match self {
            Density::Field(f) => f.memory_bytes(),
            Density::Cloud(_) => 0,
        }
    }
}

/// Emission of a density-grid medium.
#[derive(Clone, Debug)]
pub enum Emission {
    /// No emission.
    None,
    /// A constant Le (already normalised) times a scale grid.
    Radiance {
        /// Le.
        le: SpectrumValue,
        /// Multiplier grid: pbrt-v4's `Lescale` array, or a single sample of 1 when absent —
        /// which pbrt-v4 interpolates with zero outside, fading emission from 1 at the box's
        /// centre to ⅛ at its corners. nimbus does the same so its images match.
        scale: DenseGrid<f32>,
    },
    /// Blackbody emission from a temperature grid: T' = (T − offset)·scale, emitting only
    /// above 100 K, Le = scale_le · B(T') with B normalised to a peak of 1.
    Temperature {
        /// Temperatures.
        grid: Field,
        /// Subtracted from T.
        offset: f32,
        /// Multiplies T − offset.
        scale: f32,
        /// Multiplies the emission.
        le_scale: f32,
        /// Multiplier grid, as for [`Emission::Radiance`] (`uniformgrid`); none for the
        /// VDB media, which pbrt-v4 scales by a constant.
        scale_grid: Option<DenseGrid<f32>>,
        /// RGB of the peak-normalised blackbody by temperature (for RGB transport).
        table: Box<BlackbodyRgbTable>,
    },
}

/// A medium whose density varies: σ(p) = density(p) · (σa, σs).
#[derive(Clone, Debug)]
pub struct GridMedium {
    /// Medium-from-world transform.
    pub medium_from_world: Affine3A,
    /// The box (medium space) the density covers.
    pub bounds: Bounds3,
    /// Density source.
    pub density: Density,
    /// σa at density 1 (scale applied).
    pub sigma_a: SpectrumValue,
    /// σs at density 1 (scale applied).
    pub sigma_s: SpectrumValue,
    /// Emission.
    pub emission: Emission,
    /// Majorant grid over `bounds`.
    pub majorant: MajorantGrid,
    /// For a sparse density: its index space from world space in one transform (a lookup
    /// then costs one transform, not two).
    index_from_world: Affine3A,
}

/// What a medium is.
#[derive(Clone, Debug)]
pub enum MediumKind {
    /// Constant coefficients everywhere.
    Homogeneous {
        /// σa.
        sigma_a: SpectrumValue,
        /// σs.
        sigma_s: SpectrumValue,
        /// Emitted radiance.
        le: SpectrumValue,
    },
    /// Density-scaled coefficients.
    Grid(Box<GridMedium>),
    /// Per-voxel RGB coefficients.
    RgbGrid(Box<RgbGridMedium>),
}

/// A medium with its phase function.
#[derive(Clone, Debug)]
pub struct Medium {
    /// The medium's name in the scene.
    pub name: String,
    /// Coefficients.
    pub kind: MediumKind,
    /// Henyey-Greenstein asymmetry.
    pub g: f32,
    /// True when coefficients differ between channels somewhere (chromatic media need
    /// spectral MIS over channels; gray ones sample distances with any one channel).
    pub chromatic: bool,
    /// True when the medium emits.
    pub emissive: bool,
    /// The medium inside a `subsurface` material: it stands for pbrt-v4's BSSRDF, which counts
    /// as one scattering event, so the events inside do not count towards `maxdepth`.
    pub subsurface: bool,
    /// For a `subsurface` material with textured inputs: a path takes its coefficients where it
    /// enters it (the scene keeps them as functions of the entry point; [`MediumView`]), and
    /// `kind`'s are never used for transport.
    pub from_entry: bool,
}

/// A medium as one path sees it: its own coefficients, or those the path fixed where it
/// entered a medium whose coefficients come [`Medium::from_entry`].
#[derive(Clone, Copy)]
pub struct MediumView<'a, C> {
    /// The medium.
    pub medium: &'a Medium,
    /// The path's coefficients for it, homogeneous.
    pub entered: Option<MediumPoint<C>>,
}

impl<'a, C> From<&'a Medium> for MediumView<'a, C> {
    #[inline]
    fn from(medium: &'a Medium) -> MediumView<'a, C> {
        MediumView { medium, entered: None }
    }
}

impl<C: Channels> MediumView<'_, C> {
    /// Coefficients at world point `p`.
    #[inline]
    pub fn sample_point(&self, p: Vec3, lambda: &C::Lambda) -> MediumPoint<C> {
        match &self.entered {
            Some(mp) => *mp,
            None => self.medium.sample_point(p, lambda),
        }
    }

    /// Majorant segments along the ray between 0 and `t_max`.
    #[inline]
    pub fn segments(&self, ray: &Ray, t_max: f32, lambda: &C::Lambda) -> Segments<'_, C> {
        match &self.entered {
            Some(mp) => {
                let sigma_t = mp.sigma_a + mp.sigma_s;
                Segments::Single(Some(Segment { t_min: 0.0, t_max, sigma_maj: sigma_t, sigma_c: sigma_t }))
            }
            None => self.medium.segments(ray, t_max, lambda),
        }
    }
}

/// Majorant segments along a ray.
pub enum Segments<'a, C> {
    /// One segment (homogeneous media) or none.
    Single(Option<Segment<C>>),
    /// Cells of a majorant grid.
    Dda(DdaIterator<'a, C>),
}

impl<C: Channels> Iterator for Segments<'_, C> {
    type Item = Segment<C>;

    #[inline]
    fn next(&mut self) -> Option<Segment<C>> {
        match self {
            Segments::Single(s) => s.take(),
            Segments::Dda(it) => it.next(),
        }
    }
}

impl Medium {
    /// A homogeneous medium.
    pub fn homogeneous(
        name: String,
        sigma_a: SpectrumValue,
        sigma_s: SpectrumValue,
        le: SpectrumValue,
        g: f32,
    ) -> Medium {
        let chromatic = !sigma_a.is_constant() || !sigma_s.is_constant();
        let emissive = !le.is_zero();
        Medium {
            name,
            kind: MediumKind::Homogeneous { sigma_a, sigma_s, le },
            g,
            chromatic,
            emissive,
            subsurface: false,
            from_entry: false,
        }
    }

    /// A density-grid medium; builds its majorant grid (pbrt-v4 uses 16³ for grids).
    #[allow(clippy::too_many_arguments)] // mirrors pbrt-v4's GridMedium constructor
    pub fn grid(
        name: String,
        world_from_medium: Affine3A,
        bounds: Bounds3,
        density: Density,
        sigma_a: SpectrumValue,
        sigma_s: SpectrumValue,
        emission: Emission,
        g: f32,
    ) -> Medium {
        let majorant = match &density {
            Density::Field(Field::Dense(d)) => {
                MajorantGrid::new(bounds, UVec3::splat(16), |lo, hi| d.max_value(lo, hi))
                    .with_minorant(|lo, hi| d.min_value(lo, hi))
            }
            // pbrt-v4 uses 64³ for NanoVDB grids; each cell takes the maximum over the voxels
            // a lookup inside it interpolates, and the minimum over the same voxels, the
            // background included where they leave the active voxels. A lookup at index point
            // p reads voxels ⌊p⌋ and ⌊p⌋ + 1; a hundredth of a voxel of slop covers the
            // rounding between a collision's world point and the cell's index-space box.
            // (pbrt-v4 takes a whole voxel more on each side: on the Disney cloud, 2 spp,
            // the tighter cells take 31 % fewer instructions in lookups, 21 % in the render.)
            Density::Field(Field::Sparse(g)) => {
                let size = bounds.max - bounds.min;
                let footprint = |lo: Vec3, hi: Vec3| {
                    let cell =
                        Bounds3::new(bounds.min + lo * size, bounds.min + hi * size).transformed(&g.index_from_world());
                    let slop = Vec3::splat(0.01);
                    ((cell.min - slop).floor().as_ivec3(), (cell.max + slop).floor().as_ivec3() + glam::IVec3::ONE)
                };
                let (b0, b1) = g.index_bounds();
                MajorantGrid::new(bounds, UVec3::splat(64), |lo, hi| {
                    let (i0, i1) = footprint(lo, hi);
                    let (i0, i1) = (i0.max(b0), i1.min(b1));
                    if i0.cmpgt(i1).any() { 0.0 } else { g.max_over(i0, i1) }
                })
                .with_minorant(|lo, hi| {
                    let (i0, i1) = footprint(lo, hi);
                    g.min_over(i0, i1)
                })
            }
            // The procedural cloud's density never exceeds 1.
            Density::Cloud(_) => MajorantGrid::new(bounds, UVec3::ONE, |_, _| 1.0),
        };
        let chromatic = !sigma_a.is_constant() || !sigma_s.is_constant();
        let emissive = !matches!(emission, Emission::None);
        let medium_from_world = world_from_medium.inverse();
        let index_from_world = match &density {
            Density::Field(Field::Sparse(g)) => g.index_from_world() * medium_from_world,
            _ => Affine3A::IDENTITY,
        };
        Medium {
            name,
            kind: MediumKind::Grid(Box::new(GridMedium {
                medium_from_world,
                index_from_world,
                bounds,
                density,
                sigma_a,
                sigma_s,
                emission,
                majorant,
            })),
            g,
            chromatic,
            emissive,
            subsurface: false,
            from_entry: false,
        }
    }

    /// An `rgbgrid` medium (voxels packed for the transport, see [`RgbGridMedium`]; `spectral`
    /// says which); builds its 16³ majorant grid, per RGB channel where a voxel's σ is colored
    /// (`chromatic`) and the transport is RGB. Panics if the grids differ in resolution (the
    /// scene builder makes them from one nx, ny, nz).
    #[allow(clippy::too_many_arguments)] // mirrors pbrt-v4's RGBGridMedium constructor
    pub fn rgb_grid(
        name: String,
        world_from_medium: Affine3A,
        bounds: Bounds3,
        sigma_a: Option<DenseGrid<Vec4>>,
        sigma_s: Option<DenseGrid<Vec4>>,
        le: Option<DenseGrid<Vec4>>,
        le_scale: f32,
        space: ColorSpace,
        g: f32,
        chromatic: bool,
        spectral: bool,
    ) -> Medium {
        // A lookup reads every grid at the same voxel indices (unchecked in the spectral memo).
        let resolutions: Vec<UVec3> = [&sigma_a, &sigma_s, &le].into_iter().flatten().map(|g| g.resolution()).collect();
        assert!(resolutions.windows(2).all(|w| w[0] == w[1]), "an rgbgrid's grids share one resolution");
        // Per channel for RGB transport; spectral keeps one value (see `Bands`).
        let bands = if chromatic && !spectral { Bands::Rgb } else { Bands::Gray };
        let majorant = MajorantGrid::banded(bounds, UVec3::splat(16), bands, |lo, hi, out| {
            for (b, out) in out.iter_mut().enumerate() {
                let max = |g: &Option<DenseGrid<Vec4>>| {
                    g.as_ref()
                        .map_or(1.0, |g| g.max_value_by(lo, hi, |v| super::rgbgrid::band_max(v, spectral, bands, b)))
                };
                *out = max(&sigma_a) + max(&sigma_s);
            }
        });
        let emissive = le.is_some();
        Medium {
            name,
            kind: MediumKind::RgbGrid(Box::new(RgbGridMedium {
                medium_from_world: world_from_medium.inverse(),
                unit_from_world: Affine3A::from_scale(Vec3::ONE / (bounds.max - bounds.min))
                    * Affine3A::from_translation(-bounds.min)
                    * world_from_medium.inverse(),
                bounds,
                sigma_a,
                sigma_s,
                le,
                le_scale,
                space,
                majorant,
                id: super::rgbgrid::new_id(),
            })),
            g,
            chromatic,
            emissive,
            subsurface: false,
            from_entry: false,
        }
    }

    /// Bytes of grid data (0 for homogeneous media), for `--stats`.
    pub fn memory_bytes(&self) -> usize {
        match &self.kind {
            MediumKind::Homogeneous { .. } => 0,
            MediumKind::Grid(g) => {
                let e = match &g.emission {
                    Emission::Radiance { scale, .. } => scale.memory_bytes(),
                    Emission::Temperature { grid, scale_grid, .. } => {
                        grid.memory_bytes() + scale_grid.as_ref().map_or(0, |s| s.memory_bytes())
                    }
                    _ => 0,
                };
                g.density.memory_bytes() + g.majorant.memory_bytes() + e
            }
            MediumKind::RgbGrid(g) => {
                let s = |x: &Option<DenseGrid<Vec4>>| x.as_ref().map_or(0, |g| g.memory_bytes());
                s(&g.sigma_a) + s(&g.sigma_s) + s(&g.le) + g.majorant.memory_bytes()
            }
        }
    }

    /// A one-line description of how the medium is represented, for `--stats`; `spectral`
    /// says whether paths carry sampled wavelengths (else RGB channels).
    pub fn representation(&self, spectral: bool) -> String {
        let mis = if spectral { "chromatic (hero-wavelength MIS over 4)" } else { "chromatic (3-channel MIS)" };
        let channels = if self.chromatic { mis } else { "gray (1 channel)" };
        match &self.kind {
            MediumKind::Homogeneous { .. } => format!("homogeneous, closed-form, {channels}"),
            MediumKind::Grid(g) => {
                let src = match &g.density {
                    Density::Field(Field::Dense(d)) => {
                        let n = d.resolution();
                        format!("dense density grid {}x{}x{}", n.x, n.y, n.z)
                    }
                    Density::Field(Field::Sparse(s)) => {
                        let (a, b) = s.index_bounds();
                        let n = b - a + glam::IVec3::ONE;
                        format!("sparse density grid {}x{}x{} ({} bricks)", n.x, n.y, n.z, s.brick_count())
                    }
                    Density::Cloud(_) => "procedural cloud".to_string(),
                };
                let r = g.majorant.res;
                format!("{src}, majorant {}x{}x{}, {channels}", r.x, r.y, r.z)
            }
            MediumKind::RgbGrid(g) => {
                let r = g.majorant.res;
                format!("rgb grid, majorant {}x{}x{}, {mis}", r.x, r.y, r.z)
            }
        }
    }

    /// Coefficients at world point `p`, in the path's channels.
    #[inline]
    pub fn sample_point<C: Channels>(&self, p: Vec3, lambda: &C::Lambda) -> MediumPoint<C> {
        match &self.kind {
            MediumKind::Homogeneous { sigma_a, sigma_s, le } => MediumPoint {
                sigma_a: C::eval(sigma_a, lambda),
                sigma_s: C::eval(sigma_s, lambda),
                le: if self.emissive { C::eval(le, lambda) } else { C::ZERO },
            },
            MediumKind::Grid(g) => {
                let medium_point = || {
                    let pm = g.medium_from_world.transform_point3(p);
                    (pm, (pm - g.bounds.min) / (g.bounds.max - g.bounds.min))
                };
                let d = match &g.density {
                    Density::Field(Field::Sparse(s)) => s.sample(g.index_from_world.transform_point3(p)),
                    density => {
                        let (pm, pu) = medium_point();
                        density.at(pm, pu)
                    }
                };
                let le = match &g.emission {
                    Emission::None => C::ZERO,
                    Emission::Radiance { le, scale } => C::eval(le, lambda) * scale.lookup(medium_point().1),
                    Emission::Temperature { grid, offset, scale, le_scale, scale_grid, table } => {
                        let (pm, pu) = medium_point();
                        let t = (grid.at(pm, pu) - offset) * scale;
                        if t > 100.0 {
                            C::blackbody(t, table, lambda)
                                * (*le_scale * scale_grid.as_ref().map_or(1.0, |s| s.lookup(pu)))
                        } else {
                            C::ZERO
                        }
                    }
                };
                MediumPoint { sigma_a: C::eval(&g.sigma_a, lambda) * d, sigma_s: C::eval(&g.sigma_s, lambda) * d, le }
            }
            MediumKind::RgbGrid(g) => g.sample_point(p, lambda),
        }
    }

    /// Majorant segments along the world ray between 0 and `t_max` (unit direction).
    #[inline]
    pub fn segments<C: Channels>(&self, ray: &Ray, t_max: f32, lambda: &C::Lambda) -> Segments<'_, C> {
        match &self.kind {
            MediumKind::Homogeneous { sigma_a, sigma_s, .. } => {
                // σt is its own majorant and minorant.
                let sigma_t = C::eval(sigma_a, lambda) + C::eval(sigma_s, lambda);
                Segments::Single(Some(Segment { t_min: 0.0, t_max, sigma_maj: sigma_t, sigma_c: sigma_t }))
            }
            MediumKind::Grid(g) => grid_segments(
                &g.medium_from_world,
                &g.bounds,
                &g.majorant,
                ray,
                t_max,
                C::eval(&g.sigma_a, lambda) + C::eval(&g.sigma_s, lambda),
            ),
            MediumKind::RgbGrid(g) => grid_segments(&g.medium_from_world, &g.bounds, &g.majorant, ray, t_max, C::ONE),
        }
    }
}

#[inline]
fn grid_segments<'a, C: Channels>(
    medium_from_world: &Affine3A,
    bounds: &Bounds3,
    majorant: &'a MajorantGrid,
    ray: &Ray,
    t_max: f32,
    sigma_t: C,
) -> Segments<'a, C> {
    let o = medium_from_world.transform_point3(ray.o);
    let d = medium_from_world.transform_vector3(ray.d);
    match bounds.intersect_ray(o, d, t_max) {
        Some((t0, t1)) => Segments::Dda(DdaIterator::new(majorant, o, d, t0, t1, sigma_t)),
        None => Segments::Single(None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cloud_density_is_read_at_the_medium_space_point() {
        // pbrt-v4's cloud takes the medium-space point as it is: with a box of [-1, 1]³ the
        // height falloff still starts at y = 0.5, not at the box's three-quarter height.
        let cloud = Cloud { density: 1.0, wispiness: 1.0, frequency: 4.0 };
        let bounds = Bounds3::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let shift = Affine3A::from_translation(Vec3::new(3.0, 0.0, 0.0));
        let m = Medium::grid(
            "cloud".into(),
            shift,
            bounds,
            Density::Cloud(cloud),
            SpectrumValue::constant(0.0),
            SpectrumValue::constant(1.0),
            Emission::None,
            0.0,
        );
        for y in [-0.8f32, -0.2, 0.2, 0.45, 0.7] {
            let p = Vec3::new(0.3, y, -0.4);
            let s: MediumPoint<Rgb> = m.sample_point(shift.transform_point3(p), &());
            assert!((s.sigma_s.x - cloud.density_at(p)).abs() < 1e-6, "y {y}");
        }
    }
}
