//! From description to scene objects. Each entity kind has a settings reader that takes its
//! parameters with pbrt-v4's names and defaults, validates them, and leaves unknown ones to
//! be reported; rendering builds on these settings.

pub mod lights;
pub mod materials;
pub mod media;
pub mod shapes;
pub mod textures;
pub mod transport;

mod build;
mod spectra;

pub use build::{BuildOptions, BuildStats, SceneNeeds, build_scene};

use glam::{Vec2, Vec3};
use nimbus_parser::Warning;

use self::transport::{Transport, TransportChoice};
use crate::accel::Surfaces;
use crate::camera::{Camera, Differentials};
use crate::film::filter::Filter;
use crate::film::settings::FilmSettings;
use crate::lights::{Light, LightSampler, SceneSphere};
use crate::materials::subsurface::EntryCoefficients;
use crate::materials::{Material, ShadingPerturbation, resolve};
use crate::media::Medium;
use crate::samplers::settings::SamplerSettings;
use crate::spectra::PixelSensor;
use crate::textures::{TexContext, Textures};

/// Everything needed to render.
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Film settings (output name, resolution, clamp, color space).
    pub film: FilmSettings,
    /// Pixels to render: [x0, y0, x1, y1), within the full resolution.
    pub pixel_bounds: [u32; 4],
    /// The film's own pixel bounds (its `cropwindow` or `pixelbounds`, not the command
    /// line's): the whole image that parts rendered with `--pixelbounds` make up.
    pub film_bounds: [u32; 4],
    /// Sampler settings (spp, seed, kind).
    pub sampler: SamplerSettings,
    /// The reconstruction filter.
    pub filter: Filter,
    /// Surfaces and BVHs.
    pub surfaces: Surfaces,
    /// Materials, indexed by primitives.
    pub materials: Vec<Material>,
    /// Each material's bump or normal map, indexed like `materials`.
    pub shading: Vec<ShadingPerturbation>,
    /// Texture nodes.
    pub textures: Textures,
    /// The camera's footprint model, when a texture filters over it.
    pub footprint: Option<crate::camera::Footprint>,
    /// A texture also reads the footprint in (u, v) (MIP-mapped images).
    pub uv_footprint: bool,
    /// Lights (area lights first, one per emitting primitive).
    pub lights: Vec<Light>,
    /// Next-event light selection.
    pub light_sampler: LightSampler,
    /// Indices of lights at infinity.
    pub infinite_lights: Vec<u32>,
    /// Bounding sphere of the scene.
    pub sphere: SceneSphere,
    /// Whether any surface is an `interface` (shadow rays must pass through them).
    pub has_interfaces: bool,
    /// Media the scene uses (unused named media are not built).
    pub media: Vec<Medium>,
    /// Per medium, for those whose coefficients come [`Medium::from_entry`] (a textured
    /// `subsurface`), the coefficients as functions of the entry point; empty when none do.
    pub entry_coefficients: Vec<Option<EntryCoefficients>>,
    /// (inside, outside) medium of each boundary surface; primitives index this.
    pub interfaces: Vec<[u32; 2]>,
    /// Medium around the camera, or [`NONE`].
    pub camera_medium: u32,
    /// Whether any medium is chromatic (paths then pick a hero channel).
    pub has_chromatic_media: bool,
    /// Whether any medium is tracked by collisions (every kind but homogeneous, whose
    /// transmittance is closed-form): shadow rays then take a sampler dimension for their
    /// first collision.
    pub has_tracked_media: bool,
    /// Whether a path can gain anything after its last counted scattering event: a light it
    /// may hit or escape to (area or infinite), or a subsurface medium, whose events do not
    /// count. Where it cannot, volpath's paths end at that event.
    pub continues_past_max_depth: bool,
    /// The film's sensor (its imaging ratio, response curves and output matrix).
    pub sensor: PixelSensor,
    /// RGB or spectral transport, and why.
    pub transport: TransportChoice,
    /// Which camera-sample values the scene uses (the time where something moves, the lens
    /// position for a camera with a lens).
    pub camera_sample_use: crate::samplers::CameraSampleUse,
    /// pbrt-v4's `Option "disablewavelengthjitter"`: every path gets the wavelengths of u = ½.
    pub disable_wavelength_jitter: bool,
    /// Build statistics.
    pub stats: BuildStats,
    /// Warnings found while building.
    pub warnings: Vec<Warning>,
}

impl Scene {
    /// True when shapes or the camera move over the shutter interval (motion blur).
    pub fn has_motion(&self) -> bool {
        self.camera_sample_use.time
    }

    /// A medium whose coefficients a path takes from where it enters it (a `subsurface`
    /// material with textured inputs), for the methods that cannot carry them.
    pub fn entered_medium(&self) -> Option<&Medium> {
        self.media.iter().find(|m| m.from_entry)
    }

    /// The coefficients a path takes into `medium` where it enters it at the surface point
    /// `ctx` (`None` for a medium with its own).
    #[inline]
    pub fn entered_at<C: crate::channels::Channels>(
        &self,
        medium: u32,
        ctx: &TexContext,
        lambda: &C::Lambda,
    ) -> Option<crate::media::MediumPoint<C>> {
        let e = self.entry_coefficients.get(medium as usize)?.as_ref()?;
        Some(e.at(&self.textures, ctx, lambda))
    }

    /// The material that scatters at `hit` seen from `wo` (`mix` resolved), with the hit's
    /// shading normal and tangents replaced by the material's bump or normal map, and the
    /// texture lookup there: its screen-space footprint when a texture or a bump needs one
    /// (computed once per hit, with the surface derivatives at most once), from the ray's
    /// differentials `diff` where it has them, else from the camera's smallest ones.
    #[inline]
    pub fn surface_material(
        &self,
        hit: &mut crate::accel::Hit,
        wo: Vec3,
        diff: Option<&Differentials>,
    ) -> (&Material, TexContext) {
        let s = &hit.surface;
        let mut ctx = TexContext::at(s.p, s.uv, s.n);
        ctx.face = self.surfaces.shapes.face_index(hit.prim.geometry);
        let mut derivatives = None;
        if let Some(f) = &self.footprint {
            (ctx.dpdx, ctx.dpdy) = diff.and_then(|d| d.dp_dxy(s.p, s.n)).unwrap_or_else(|| f.dp_dxy(s.p, s.n));
            if self.uv_footprint {
                let d = self.surfaces.derivatives(hit);
                (ctx.duvdx, ctx.duvdy) = uv_footprint(d.dpdu, d.dpdv, ctx.dpdx, ctx.dpdy);
                derivatives = Some(d);
            }
        }
        let id = resolve(&self.materials, hit.prim.material, &self.textures, &ctx, wo);
        let shading = &self.shading[id as usize];
        if !shading.is_none() {
            let d = derivatives.unwrap_or_else(|| self.surfaces.derivatives(hit));
            // A bump steps by the (u, v) footprint even where no texture reads it.
            if self.footprint.is_some() && !self.uv_footprint {
                (ctx.duvdx, ctx.duvdy) = uv_footprint(d.dpdu, d.dpdv, ctx.dpdx, ctx.dpdy);
            }
            shading.apply(&self.textures, &mut hit.surface, &d, &ctx);
        }
        (&self.materials[id as usize], ctx)
    }

    /// The differentials of the ray leaving `hit` (its material looked up in `ctx`) along `wi`
    /// after a perfectly specular reflection or transmission (relative index `eta`) of a ray
    /// that arrived along −`wo` with differentials `diff` (pbrt-v4's `SpawnRay` with specular
    /// flags; the shading normal's change across the footprint from the shape's ∂n/∂u, ∂n/∂v).
    #[allow(clippy::too_many_arguments)]
    pub fn specular_differentials(
        &self,
        hit: &crate::accel::Hit,
        ctx: &TexContext,
        diff: &Differentials,
        wo: Vec3,
        wi: Vec3,
        transmission: bool,
        eta: f32,
    ) -> Option<Differentials> {
        let d = self.surfaces.derivatives(hit);
        let (duvdx, duvdy) = uv_footprint(d.dpdu, d.dpdv, ctx.dpdx, ctx.dpdy);
        let dndx = d.dndu * duvdx.x + d.dndv * duvdx.y;
        let dndy = d.dndu * duvdy.x + d.dndv * duvdy.y;
        let s = &hit.surface;
        diff.specular(s.p, (ctx.dpdx, ctx.dpdy), s.ns, (dndx, dndy), wo, wi, transmission.then_some(eta))
    }

    /// The matrix from what the film accumulates to output RGB: for RGB transport samples are
    /// output RGB already and only the imaging ratio is left; for spectral transport they are
    /// sensor RGB (imaging ratio included), converted as pbrt-v4's RGB film does.
    pub fn film_output(&self) -> glam::DMat3 {
        match self.transport.transport {
            Transport::Rgb => glam::DMat3::from_diagonal(glam::DVec3::splat(f64::from(self.sensor.imaging_ratio()))),
            Transport::Spectral => self.sensor.output_rgb_from_sensor_rgb(),
        }
    }
}

/// Emission of an area light: pbrt-v4's photometric normalisation and `power`.
/// ∂(u, v)/∂x and ∂(u, v)/∂y from the screen-space footprint (`dpdx`, `dpdy`) and the
/// surface's ∂p/∂u, ∂p/∂v, by least squares as pbrt-v4's `ComputeDifferentials` does
/// (clamped to ±10⁸; zero where the parameterisation degenerates).
fn uv_footprint(dpdu: Vec3, dpdv: Vec3, dpdx: Vec3, dpdy: Vec3) -> (Vec2, Vec2) {
    let (a00, a01, a11) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
    let inv_det = 1.0 / (a00 * a11 - a01 * a01);
    let inv_det = if inv_det.is_finite() { inv_det } else { 0.0 };
    let solve = |d: Vec3| {
        let (b0, b1) = (dpdu.dot(d), dpdv.dot(d));
        let du = (a11 * b0 - a01 * b1) * inv_det;
        let dv = (a00 * b1 - a01 * b0) * inv_det;
        let clamp = |v: f32| if v.is_finite() { v.clamp(-1e8, 1e8) } else { 0.0 };
        Vec2::new(clamp(du), clamp(dv))
    };
    (solve(dpdx), solve(dpdy))
}

#[cfg(test)]
mod footprint_tests {
    use super::*;

    #[test]
    fn uv_footprints_solve_the_tangent_plane() {
        // p = (2u, 3v, 0): a step (0.2, 0.3, 0) is (du, dv) = (0.1, 0.1); one along the
        // normal has no (u, v) component; a degenerate parameterisation gives zero.
        let (dx, dy) =
            uv_footprint(Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0), Vec3::new(0.2, 0.3, 0.0), Vec3::Z);
        assert!((dx - Vec2::new(0.1, 0.1)).length() < 1e-6 && dy.length() < 1e-6, "{dx} {dy}");
        // A sheared parameterisation: p = u·(1, 0, 0) + v·(1, 1, 0).
        let (dx, _) = uv_footprint(Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 0.5, 0.0), Vec3::ZERO);
        assert!((dx - Vec2::new(-0.5, 0.5)).length() < 1e-6, "{dx}");
        let (dx, dy) = uv_footprint(Vec3::X, Vec3::X, Vec3::ONE, Vec3::ONE);
        assert!(dx == Vec2::ZERO && dy == Vec2::ZERO);
    }
}
