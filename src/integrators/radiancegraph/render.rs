//! Rendering from the radiance cache (thesis Sec. 4.6): a camera ray is delta-tracked to its
//! first real scattering event p (the MC estimate of Eq. 4.24's integral over the ray) and
//! returns Σ_lights L_e · L'_search(p), where L'_search (Eq. 4.25) is the inverse-square-
//! distance-weighted mean of the transported radiance of the nodes whose render search range
//! contains p.

use glam::{IVec3, Vec2, Vec3};

use super::similarity::Similarity;
use super::transport::Source;
use super::volume::{MAX_LIGHTS, collision_walk, sample_area_lights, transmittance_from_inside};
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::integrators::RayIntegrator;
use crate::integrators::common::{PathConfig, PathRecorder, PathStrategy, RayStats, trace_path};
use crate::math::cell_map::CellMap;
use crate::media::phase::HenyeyGreenstein;
use crate::samplers::Sampler;
use crate::sampling::rng::{Pcg32, hash_sample};
use crate::scene::Scene;
use crate::spectra::SpectrumValue;

/// The nodes' transported radiance, searchable by position.
pub struct RadianceCache {
    positions: Vec<Vec3>,
    /// Squared render search range per node.
    ranges_sq: Vec<f32>,
    /// Transported radiance, light-major: `radiance[(light * n + node) * k + c]` with k
    /// values per node (1, or the directional coefficients of an anisotropic medium).
    radiance: Vec<f32>,
    lights: usize,
    /// Values per node and light.
    k: usize,
    /// Cell size: twice the mean search range.
    cell: f32,
    /// Per cell, the range in `members` of the nodes whose search sphere reaches into it, so
    /// a lookup reads one cell.
    cells: CellMap<(u32, u32)>,
    members: Vec<u32>,
}

impl RadianceCache {
    /// Bytes held: per node its position, range and one scalar per light; the cell map.
    pub fn memory_bytes(&self) -> usize {
        self.positions.capacity() * 12
            + self.ranges_sq.capacity() * 4
            + self.radiance.capacity() * 4
            + self.members.capacity() * 4
            // hashbrown: key, value and one control byte per bucket.
            + self.cells.capacity() * (12 + 8 + 1)
    }

    /// A cache over nodes at `positions` with render search ranges `ranges` and, per light,
    /// the transported radiance of each node: one scalar, or (node-major) its directional
    /// coefficients.
    pub fn new(positions: Vec<Vec3>, ranges: Vec<f32>, radiance: Vec<Vec<f32>>) -> RadianceCache {
        let n = positions.len();
        let k = radiance.first().map_or(1, |r| r.len().checked_div(n).unwrap_or(1)).max(1);
        let mean = ranges.iter().map(|&r| f64::from(r)).sum::<f64>() / n.max(1) as f64;
        // Cells of twice the mean range: a node's search sphere reaches into about 8 of them
        // (4 bytes each), a lookup checks the nodes of one.
        let cell = (2.0 * mean as f32).max(f32::MIN_POSITIVE);
        let key = |p: Vec3| (p / cell).floor().as_ivec3();
        let for_cells = |i: usize, f: &mut dyn FnMut(IVec3)| {
            let (p, r) = (positions[i], ranges[i]);
            let (lo, hi) = (key(p - Vec3::splat(r)), key(p + Vec3::splat(r)));
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        f(IVec3::new(x, y, z));
                    }
                }
            }
        };
        // Two passes (count, then fill) instead of sorting (cell, node) pairs: no array of
        // pairs, which was 16 bytes for each of them.
        let mut cells: CellMap<(u32, u32)> = CellMap::default();
        for i in 0..n {
            for_cells(i, &mut |c| cells.entry(c).or_insert((0, 0)).1 += 1);
        }
        // Cell ranges in `members`, in cell order so the layout does not depend on hashing.
        let mut keys: Vec<IVec3> = cells.keys().copied().collect();
        keys.sort_unstable_by_key(|c| c.to_array());
        let mut start = 0u32;
        for k in &keys {
            let e = cells.get_mut(k).expect("counted");
            let count = e.1;
            *e = (start, start);
            start += count;
        }
        drop(keys);
        // Fill: the second field counts up to the cell's end; nodes in index order.
        let mut members = vec![0u32; start as usize];
        for i in 0..n {
            for_cells(i, &mut |c| {
                let e = cells.get_mut(&c).expect("counted");
                members[e.1 as usize] = i as u32;
                e.1 += 1;
            });
        }
        let lights = radiance.len();
        RadianceCache {
            ranges_sq: ranges.iter().map(|r| r * r).collect(),
            radiance: radiance.into_iter().flatten().collect(),
            positions,
            lights,
            k,
            cell,
            cells,
            members,
        }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True without nodes.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Eq. 4.25 at `p` for light `light`: 0 where no node's range contains `p`. In an
    /// anisotropic medium, each node's radiance leaving toward `wo` (clamped at 0: a band-2
    /// function can dip below it).
    pub fn lookup_toward(&self, p: Vec3, light: usize, wo: Vec3) -> f32 {
        if self.k == 1 {
            return self.lookup(p, light);
        }
        let y = super::sh::basis(wo);
        let base = light * self.positions.len() * self.k;
        let value = |i: usize| {
            let c = &self.radiance[base + i * self.k..base + (i + 1) * self.k];
            c.iter().zip(&y).map(|(a, b)| a * b).sum::<f32>()
        };
        self.weighted_mean(p, value).max(0.0) as f32
    }

    /// Eq. 4.25 at `p` for light `light`: 0 where no node's range contains `p`.
    pub fn lookup(&self, p: Vec3, light: usize) -> f32 {
        let n = self.positions.len();
        self.weighted_mean(p, |i| self.radiance[light * n + i]) as f32
    }

    /// The inverse-square-distance-weighted mean of `value` over the nodes whose range
    /// contains `p` (Eq. 4.25), 0 when none does.
    #[inline]
    fn weighted_mean(&self, p: Vec3, value: impl Fn(usize) -> f32) -> f64 {
        let Some(&(s, e)) = self.cells.get(&(p / self.cell).floor().as_ivec3()) else { return 0.0 };
        let (mut sum, mut weight) = (0.0f64, 0.0f64);
        for &i in &self.members[s as usize..e as usize] {
            let i = i as usize;
            let d2 = self.positions[i].distance_squared(p);
            if d2 < self.ranges_sq[i] {
                // A point at a node's centre would weigh infinitely: clamp the distance to a
                // millionth of the range.
                let w = 1.0 / f64::from(d2.max(self.ranges_sq[i] * 1e-12));
                sum += w * f64::from(value(i));
                weight += w;
            }
        }
        if weight > 0.0 { sum / weight } else { 0.0 }
    }

    /// Number of lights.
    pub fn lights(&self) -> usize {
        self.lights
    }
}

/// How a camera ray integrates Eq. 4.24, ∫ T_r σs L' dt, through the medium.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Estimator {
    /// The thesis's: delta tracking to the first real event; a scattering event reads the
    /// cache there, absorption and leaving read nothing.
    #[default]
    DeltaTracking,
    /// Every tentative collision reads the cache, weighted by the ratio-tracked transmittance
    /// to it and σs/σmaj (the collision estimator of the same integral): more lookups per
    /// sample, no zero-or-one outcome.
    Collision,
}

/// The `radiancegraph` integrator: a cache and the lights its scalars belong to.
pub struct RadianceGraphIntegrator {
    cache: RadianceCache,
    estimator: Estimator,
    /// Each cached light's radiance, in cache order.
    lights: Vec<SpectrumValue>,
    /// Uniform infinite lights, seen directly by rays that leave the medium.
    sky: Vec<SpectrumValue>,
    /// Bytes of the graph at its largest: the build's peak, or the cache when it was read
    /// from a file.
    graph_bytes: usize,
    /// In an anisotropic medium: HG's g and where each cached light comes from. The cache
    /// then holds the bounces after the first, and single scattering is computed at the
    /// camera ray's event with the exact phase function.
    phase: Option<(f32, Vec<Source>)>,
    /// The path loop up to the medium (the scene's `maxdepth` bounds surface bounces).
    path: PathConfig,
    /// A warning for the render's summary (a graph sized too coarse for its medium).
    note: Option<String>,
    /// Where the graph holds the similar medium of a strongly forward-scattering one: camera
    /// paths read it at this scattering event, not the first.
    similarity: Option<Similarity>,
    /// The scene's path depth, which `path.max_depth` raises to reach that event.
    scene_max_depth: u32,
}

impl RadianceGraphIntegrator {
    /// An integrator over `cache`, whose scalars belong to `lights` (in order); `sky` are the
    /// uniform lights a camera ray sees when it leaves the scene.
    pub fn new(cache: RadianceCache, lights: Vec<SpectrumValue>, sky: Vec<SpectrumValue>) -> RadianceGraphIntegrator {
        assert_eq!(cache.lights(), lights.len());
        let graph_bytes = cache.memory_bytes();
        RadianceGraphIntegrator {
            cache,
            estimator: Estimator::default(),
            lights,
            sky,
            graph_bytes,
            phase: None,
            path: PathConfig::volpath(5, false),
            note: None,
            similarity: None,
            scene_max_depth: 5,
        }
    }

    /// The same over the graph of the similar isotropic medium: camera paths read it at their
    /// `similarity.read_at`-th scattering event, the events before it traced exactly.
    pub fn with_similarity(mut self, similarity: Similarity) -> RadianceGraphIntegrator {
        self.similarity = Some(similarity);
        let depth = self.scene_max_depth;
        self.with_max_depth(depth)
    }

    /// The same in a medium scattering by HG with asymmetry `g`, its lights coming from
    /// `sources` (in cache order).
    pub fn with_phase(mut self, g: f32, sources: Vec<Source>) -> RadianceGraphIntegrator {
        assert_eq!(sources.len(), self.lights.len());
        self.phase = Some((g, sources));
        self
    }

    /// The same, with the graph's build having peaked at `bytes` (more than the cache kept).
    pub fn with_build_peak(mut self, bytes: usize) -> RadianceGraphIntegrator {
        self.graph_bytes = self.graph_bytes.max(bytes);
        self
    }

    /// The same with paths of at most `max_depth` scattering events before the medium: at
    /// least as many as reach the event that reads the graph of a similar medium, which
    /// transports light to convergence whatever the scene's depth.
    pub fn with_max_depth(mut self, max_depth: u32) -> RadianceGraphIntegrator {
        self.scene_max_depth = max_depth;
        self.path.max_depth = max_depth.max(self.similarity.map_or(0, |s| s.read_at));
        self
    }

    /// The same with a warning for the render's summary.
    pub fn with_note(mut self, note: Option<String>) -> RadianceGraphIntegrator {
        self.note = note;
        self
    }

    /// The same with another estimator along camera rays.
    pub fn with_estimator(mut self, estimator: Estimator) -> RadianceGraphIntegrator {
        self.estimator = estimator;
        self
    }

    /// Σ_lights L_e · L'_search(p), weighted by `w`, leaving toward `wo`: in an anisotropic
    /// medium, single scattering with the exact phase function (one ratio-tracked shadow
    /// ray per light) plus the cache's later bounces toward `wo`.
    #[inline]
    fn radiance_at<C: Channels>(&self, scene: &Scene, p: Vec3, wo: Vec3, w: f32, le: &[C], rng: &mut Pcg32) -> C {
        let mut l = C::ZERO;
        for (i, le) in le.iter().enumerate() {
            let mut v = self.cache.lookup_toward(p, i, wo);
            if let Some((g, sources)) = &self.phase {
                v += single_scattering(scene, p, wo, *g, &sources[i], rng);
            }
            if v > 0.0 {
                l += *le * (w * v);
            }
        }
        l
    }
}

impl RayIntegrator for RadianceGraphIntegrator {
    fn name(&self) -> &'static str {
        super::METHOD.name
    }

    fn report(&self) -> Vec<String> {
        let mut lines = vec![format!(
            "graph       {} nodes, cache {:.2} MiB, {:.2} MiB at the graph's largest",
            self.cache.positions.len(),
            self.cache.memory_bytes() as f64 / (1 << 20) as f64,
            self.graph_bytes as f64 / (1 << 20) as f64
        )];
        if let Some(s) = self.similarity {
            lines.push(format!(
                "similarity  the medium's g = {} is beyond the directional graph's {}: the graph holds the similar \
                 isotropic medium (σs(1 − g)), read at each camera path's scattering event {}, the events before it \
                 traced exactly",
                s.g,
                super::volume::MAX_G,
                s.read_at
            ));
            lines.push(format!(
                "warning     the similar medium's graph transports light until it leaves the medium, not to the scene's \
                 maxdepth {}: compare with volpath at a maxdepth long enough for its paths to end by themselves \
                 (on the Disney cloud maxdepth 100 cuts off 26 % of the light)",
                self.scene_max_depth
            ));
        }
        lines.extend(self.note.as_ref().map(|n| format!("warning     {n}")));
        lines
    }

    fn precomputed_bytes(&self) -> usize {
        self.graph_bytes
    }

    fn li<C: Channels>(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut C::Lambda,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> C {
        match self.estimator {
            // The shared path loop up to the first real scattering event in the medium, which
            // reads the cache: surfaces beside the medium, area lights and the sky are traced
            // as volpath traces them.
            Estimator::DeltaTracking => {
                let mut reader = CacheReader { graph: self, scene };
                trace_path(scene, ray, scene.camera_medium, lambda, sampler, &self.path, &mut reader, stats)
            }
            Estimator::Collision => self.li_collision(scene, ray, lambda, sampler, stats),
        }
    }
}

/// The path loop's view of the cache: a path ends at its first real scattering event in the
/// medium with the cache's radiance there.
struct CacheReader<'a> {
    graph: &'a RadianceGraphIntegrator,
    scene: &'a Scene,
}

impl PathStrategy for CacheReader<'_> {
    fn ends_in_medium(&self, depth: u32) -> bool {
        depth >= self.graph.similarity.map_or(1, |s| s.read_at)
    }

    fn medium_estimate<C: Channels>(&mut self, _medium: u32, p: Vec3, wo: Vec3, lambda: &C::Lambda, u: f32) -> C {
        let mut le = [C::ZERO; MAX_LIGHTS];
        for (slot, l) in le.iter_mut().zip(&self.graph.lights) {
            *slot = C::eval(l, lambda);
        }
        let mut rng = Pcg32::new(hash_sample(u, Vec2::ZERO), hash_sample(u, Vec2::ONE));
        self.graph.radiance_at(self.scene, p, wo, 1.0, &le[..self.graph.lights.len()], &mut rng)
    }
}

impl<C: Channels> PathRecorder<C> for CacheReader<'_> {}

impl RadianceGraphIntegrator {
    /// The collision estimator along the camera ray (a scene whose surfaces are the medium's
    /// boundary only: the method checks).
    fn li_collision<C: Channels>(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut C::Lambda,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> C {
        let medium = &scene.media[0];
        let mut rng = Pcg32::new(hash_sample(sampler.get_1d(), Vec2::ZERO), hash_sample(sampler.get_1d(), Vec2::ONE));
        // The first tentative collision comes from the sampler, as in volpath (pbrt-v4's
        // SampleT_maj): a pixel's samples then cover the depths along its rays evenly, where
        // the generator's values fall where they may. Later ones come from the generator.
        let mut u_first = Some(sampler.get_1d());
        // The lights' radiance in the path's channels, once per sample (at most a few lights).
        let mut le = [C::ZERO; MAX_LIGHTS];
        let n_lights = self.lights.len();
        for (slot, l) in le.iter_mut().zip(&self.lights) {
            *slot = C::eval(l, lambda);
        }
        let le = &le[..n_lights];
        let mut ray = ray;
        let mut inside = false;
        // What reaches the camera from beyond the current point (the collision estimator's
        // transmittance so far; 1 for delta tracking, whose outcomes are all or nothing).
        let mut beta = 1.0f32;
        let mut l = C::ZERO;
        // A closed boundary is crossed an even number of times; 64 bounds a pathological mesh.
        for _ in 0..64 {
            let hit = scene.surfaces.intersect(&ray, f32::INFINITY);
            stats.bounce += 1;
            if inside {
                let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.surface.t);
                let u = u_first.take().unwrap_or_else(|| rng.uniform());
                beta = collision_walk(medium, &ray, t_max, u, &mut rng, beta, |p, mp, w, rng| {
                    l += self.radiance_at(scene, p, -ray.d, w * mp.sigma_s[0], le, rng);
                });
                if beta == 0.0 {
                    return l;
                }
            }
            match hit {
                None => {
                    for s in &self.sky {
                        l += C::eval(s, lambda) * beta;
                    }
                    return l;
                }
                Some(h) => {
                    inside = ray.d.dot(h.surface.n) < 0.0;
                    ray = h.surface.spawn_ray(ray.d);
                }
            }
        }
        l
    }
}

/// Light from `source` scattered once at `p` toward `wo` by HG with asymmetry `g`, per unit
/// of the light's radiance (a point light's intensity): T_r to the light times the phase
/// function for a distant light, and over r² for a point light; for light from every
/// direction, the transmittance along a direction sampled by the phase function (whose
/// weight p/pdf is 1).
fn single_scattering(scene: &Scene, p: Vec3, wo: Vec3, g: f32, source: &Source, rng: &mut Pcg32) -> f32 {
    let (toward_light, phase) = match source {
        Source::Along(dir) => (-*dir, super::sh::hg(dir.dot(wo), g)),
        Source::Area(lights) => {
            // One light sample, as the graph's direct light.
            let Some((wi, dist, pdf)) = sample_area_lights(scene, lights, p, rng) else { return 0.0 };
            let t = transmittance_from_inside(scene, &scene.media[0], &Ray::new(p, wi), dist, rng);
            return t * super::sh::hg(-wi.dot(wo), g) / pdf;
        }
        Source::Reflected(light) => {
            // A direction by the phase function (weight 1) and the light the surfaces reflect
            // along it. A colored surface was refused where the build's direct light met it;
            // one it never met counts as dark here.
            let u = Vec2::new(rng.uniform(), rng.uniform());
            let Some(s) = HenyeyGreenstein::new(g).sample_p(wo, u) else { return 0.0 };
            return super::volume::reflected_along(scene, &scene.media[0], &Ray::new(p, s.wi), light, rng)
                .unwrap_or(0.0);
        }
        Source::Point(pos) => {
            let (v, d2) = (*pos - p, pos.distance_squared(p));
            let to_light = v / d2.sqrt();
            let t = transmittance_from_inside(scene, &scene.media[0], &Ray::new(p, to_light), d2.sqrt(), rng);
            return t * super::sh::hg(-to_light.dot(wo), g) / d2;
        }
        Source::Everywhere => {
            let u = Vec2::new(rng.uniform(), rng.uniform());
            match HenyeyGreenstein::new(g).sample_p(wo, u) {
                Some(s) => (s.wi, 1.0),
                None => return 0.0,
            }
        }
    };
    phase * transmittance_from_inside(scene, &scene.media[0], &Ray::new(p, toward_light), f32::INFINITY, rng)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 4.25 by hand: nodes at x = 0 and x = 1 (ranges 1 and 0.5) with radiance 2 and 6;
    /// at x = 0.25 only node 0 reaches (node 1 is 0.75 away, beyond 0.5): 2. At x = 0.6 both
    /// reach, with weights 1/0.36 and 1/0.16: (2/0.36 + 6/0.16) / (1/0.36 + 1/0.16) = 4.769….
    #[test]
    fn eq_4_25_by_hand() {
        let c = RadianceCache::new(vec![Vec3::ZERO, Vec3::X], vec![1.0, 0.5], vec![vec![2.0, 6.0]]);
        assert_eq!(c.lookup(Vec3::new(0.25, 0.0, 0.0), 0), 2.0);
        let want = (2.0 / 0.36 + 6.0 / 0.16) / (1.0 / 0.36 + 1.0 / 0.16);
        assert!((c.lookup(Vec3::new(0.6, 0.0, 0.0), 0) - want).abs() < 1e-5);
        assert_eq!(c.lookup(Vec3::new(3.0, 0.0, 0.0), 0), 0.0);
        assert_eq!(c.lookup(Vec3::ZERO, 0), 2.0);
    }
}
