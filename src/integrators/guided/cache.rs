//! `--guide-cache FILE`: the trained trees are view-independent, so a later render (another
//! camera, another spp) reuses them. The file is nimbus's own little-endian binary: a magic
//! number, a version, a hash of what the trees depend on in the scene (its media, probed, its
//! lights and its extent) and one of the training parameters, then the trees. A file from
//! another scene, other training settings or another nimbus version is refused by name.

use super::super::prepared::{FileKind, Header, read_file, write_file};
use crate::error::Error;
use crate::math::fnv::Fnv;
use std::path::Path;

use glam::{Affine3A, Vec3};

use super::dtree::DTree;
use super::sdtree::SdTree;
use super::settings::GuidedSettings;
use super::train::{Guide, TrainingStats};
use crate::color::Rgb;
use crate::geometry::Bounds3;
use crate::media::{Medium, MediumKind};
use crate::scene::Scene;

/// The guide cache's kind: its header is every prepared file's ([`super::super::prepared`]).
const KIND: FileKind = FileKind {
    magic: b"NIMBUSGD",
    version: 2,
    what: "guide cache",
    remedy: "delete it or name another file to train anew",
    settings: "training parameters (maxdepth, trainingiterations, photons, streethreshold, dtreethreshold, \
               maxmemory or refractedshare)",
};

/// Probes a grid medium at 16³ points of its box (σa and σs), so equal media hash equally
/// whatever file they were read from, and changed ones differently.
fn probe(h: &mut Fnv, m: &Medium, from_world: &Affine3A, bounds: &Bounds3) {
    let world_from = from_world.inverse();
    let n = 16;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let t = (Vec3::new(x as f32, y as f32, z as f32) + 0.5) / n as f32;
                let p = world_from.transform_point3(bounds.min + (bounds.max - bounds.min) * t);
                let mp = m.sample_point::<Rgb>(p, &());
                mp.sigma_a.to_array().iter().chain(mp.sigma_s.to_array().iter()).for_each(|&v| h.f32(v));
            }
        }
    }
}

/// A hash of what the trees depend on in `scene`.
pub fn scene_hash(scene: &Scene) -> u64 {
    let mut h = Fnv::new();
    for m in &scene.media {
        h.bytes(m.name.as_bytes());
        h.f32(m.g);
        match &m.kind {
            MediumKind::Homogeneous { sigma_a, sigma_s, le } => {
                h.bytes(format!("{sigma_a:?}{sigma_s:?}{le:?}").as_bytes())
            }
            MediumKind::Grid(g) => probe(&mut h, m, &g.medium_from_world, &g.bounds),
            MediumKind::RgbGrid(g) => probe(&mut h, m, &g.medium_from_world, &g.bounds),
        }
    }
    for light in &scene.lights {
        h.bytes(format!("{light:?}").as_bytes());
    }
    h.f32(scene.sphere.radius);
    scene.sphere.center.to_array().iter().for_each(|&v| h.f32(v));
    h.finish()
}

/// A hash of the parameters training depends on.
fn settings_hash(s: &GuidedSettings) -> u64 {
    let mut h = Fnv::new();
    // `refractedshare` ends training early when no medium will be guided.
    let key = (
        s.max_depth,
        s.training_iterations,
        s.photons,
        s.stree_threshold,
        s.dtree_threshold,
        s.max_memory_mib,
        s.refracted_share,
    );
    h.bytes(format!("{key:?}").as_bytes());
    h.finish()
}

/// Writes the trees of `guide`, trained for `scene` with `settings`.
pub fn save(path: &Path, scene: &Scene, settings: &GuidedSettings, guide: &Guide) -> crate::Result<()> {
    let mut out = Vec::new();
    KIND.write_header(Header { scene_hash: scene_hash(scene), settings_hash: settings_hash(settings) }, &mut out);
    let s = &guide.stats;
    out.extend_from_slice(&s.photons.to_le_bytes());
    out.extend_from_slice(&s.deposits.to_le_bytes());
    out.extend_from_slice(&s.seconds.to_le_bytes());
    out.extend_from_slice(&(guide.trees.len() as u32).to_le_bytes());
    for (t, r) in guide.trees.iter().zip(&guide.refracted) {
        out.extend_from_slice(&r.to_le_bytes());
        match t {
            None => out.push(0),
            Some(t) => {
                out.push(1);
                t.write(&mut out);
            }
        }
    }
    write_file(path, &out)
}

/// Why a guide cache's contents cannot be used (after its header was accepted).
fn bad(path: &Path, why: impl std::fmt::Display) -> Error {
    Error::malformed(path, format!("the guide cache cannot be used: {why}"))
}

/// A cursor over a cache file's bytes that reports truncation.
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl Reader<'_> {
    /// The next `n` bytes.
    pub fn take(&mut self, n: usize) -> crate::Result<&[u8]> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| bad(self.path, "the file is truncated"))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    /// A little-endian u32.
    pub fn u32(&mut self) -> crate::Result<u32> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    /// A little-endian u64.
    pub fn u64(&mut self) -> crate::Result<u64> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    /// A little-endian f32.
    pub fn f32(&mut self) -> crate::Result<f32> {
        Ok(f32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    /// A count of items of at least `item_bytes` each, checked against what is left.
    pub fn count(&mut self, item_bytes: usize) -> crate::Result<usize> {
        let n = self.u32()? as usize;
        if n.saturating_mul(item_bytes) > self.bytes.len() - self.at {
            return Err(bad(self.path, format!("a count of {n} exceeds the file")));
        }
        Ok(n)
    }
}

/// Reads trees saved for `scene` and `settings` from `path`.
pub fn load(path: &Path, scene: &Scene, settings: &GuidedSettings) -> crate::Result<Guide> {
    let bytes = read_file(path)?;
    let (_, body) = KIND.read_header(&bytes, path, Some(scene_hash(scene)), Some(settings_hash(settings)))?;
    let mut r = Reader { bytes: body, at: 0, path };
    let photons = r.u64()?;
    let stats = TrainingStats {
        photons,
        // Round k traces photons·2^k after the pilot.
        rounds: ((photons.saturating_sub(super::train::PILOT) / settings.photons.max(1) as u64) + 1).ilog2(),
        deposits: r.u64()?,
        seconds: f64::from_le_bytes(r.take(8)?.try_into().unwrap()),
    };
    let n = r.count(1)?;
    if n != scene.media.len() {
        return Err(bad(path, format!("it has trees for {n} media, the scene has {}", scene.media.len())));
    }
    let (mut trees, mut refracted) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for _ in 0..n {
        let share = r.f32()?;
        if !(0.0..=1.0).contains(&share) {
            return Err(bad(path, format!("a medium's refracted share is {share}")));
        }
        refracted.push(share);
        trees.push(match r.take(1)?[0] {
            0 => None,
            1 => Some(SdTree::read(&mut r)?),
            t => return Err(bad(path, format!("unknown tree tag {t}"))),
        });
    }
    if r.at != body.len() {
        return Err(bad(path, "it has bytes after its trees"));
    }
    let active = trees.iter().map(Option::is_some).collect();
    Ok(Guide { trees, refracted, active, stats, fluence: Vec::new() })
}

/// Serialisation of the trees (here, so the tree modules stay about trees).
impl SdTree {
    fn write(&self, out: &mut Vec<u8>) {
        let b = self.bounds();
        for v in [b.min, b.max] {
            v.to_array().iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        }
        let (nodes, dtrees) = self.parts();
        out.extend_from_slice(&(nodes.len() as u32).to_le_bytes());
        for &(axis, child, dtree) in &nodes {
            out.push(axis);
            out.extend_from_slice(&child.to_le_bytes());
            out.extend_from_slice(&dtree.to_le_bytes());
        }
        out.extend_from_slice(&(dtrees.len() as u32).to_le_bytes());
        for d in dtrees {
            let (count, nodes) = d.parts();
            out.extend_from_slice(&count.to_le_bytes());
            out.extend_from_slice(&(nodes.len() as u32).to_le_bytes());
            for (sums, children) in nodes {
                sums.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
                children.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
            }
        }
    }

    fn read(r: &mut Reader<'_>) -> crate::Result<SdTree> {
        let mut v = [0.0f32; 6];
        for x in &mut v {
            *x = r.f32()?;
        }
        let bounds = Bounds3::new(Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
        let n = r.count(9)?;
        let mut nodes = Vec::with_capacity(n);
        for _ in 0..n {
            let axis = r.take(1)?[0];
            nodes.push((axis, r.u32()?, r.u32()?));
        }
        let n = r.count(12)?;
        let mut dtrees = Vec::with_capacity(n);
        for _ in 0..n {
            let count = r.u64()?;
            let m = r.count(32)?;
            let mut dn = Vec::with_capacity(m);
            for _ in 0..m {
                let mut sums = [0.0f32; 4];
                for s in &mut sums {
                    *s = r.f32()?;
                }
                let mut children = [0u32; 4];
                for c in &mut children {
                    *c = r.u32()?;
                }
                dn.push((sums, children));
            }
            dtrees.push(DTree::from_parts(count, dn).map_err(|e| bad(r.path, e))?);
        }
        SdTree::from_parts(bounds, nodes, dtrees).map_err(|e| bad(r.path, e))
    }
}
