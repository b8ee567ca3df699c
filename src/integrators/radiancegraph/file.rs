//! nimbus's graph file: the radiance cache a render needs, in a compact versioned binary.
//!
//! Layout (little-endian): magic `NIMBUSRG`; format version u32; scene hash u64 (the medium
//! and the lights, see [`scene_hash`]); config hash u64; bounces asked and reached u32 ×2;
//! node radius f32; light count u32; values per node and light u32 (1, or the directional
//! coefficients of an anisotropic medium); node count u64; then positions (3 × f32 per node),
//! render search ranges (f32 per node) and per light the transported radiance (that many f32
//! per node). 20 bytes per node for one light in an isotropic medium; the thesis's text file
//! holds the same in ≈ 60.

use crate::math::fnv::Fnv;
use std::path::Path;

use glam::Vec3;

use super::super::prepared::{FileKind, Header, read_file, write_file};
use super::config::GraphConfig;
use super::volume::Volume;
use crate::color::Rgb;
use crate::error::{Error, Result};

/// The graph file's kind: its header is every prepared file's ([`super::super::prepared`]).
pub const KIND: FileKind = FileKind {
    magic: b"NIMBUSRG",
    version: 2,
    what: "graph",
    remedy: "rebuild it with `nimbus graph build`",
    settings: "graph config",
};

/// What a graph file holds.
#[derive(Clone, Debug, PartialEq)]
pub struct GraphFile {
    /// [`scene_hash`] of the scene it was built for.
    pub scene_hash: u64,
    /// [`config_hash`] of the configuration it was built with.
    pub config_hash: u64,
    /// Bounces asked for.
    pub bounces: u32,
    /// Bounces reached.
    pub bounces_done: u32,
    /// Node radius.
    pub node_radius: f32,
    /// Values per node and light: 1, or [`super::sh::COEFFS`] in an anisotropic medium.
    pub coefficients: u32,
    /// Node positions.
    pub positions: Vec<Vec3>,
    /// Render search ranges.
    pub ranges: Vec<f32>,
    /// Per light, per node: transported radiance scalars.
    pub radiance: Vec<Vec<f32>>,
}

/// A hash of what the graph depends on in the scene: the medium, probed at 16³ points of its
/// bounds (σa and σs, so equal media hash equally whatever file they come from), the
/// bounds, the phase function's g, and each light's kind, direction and radiance.
pub fn scene_hash(volume: &Volume) -> u64 {
    let mut h = Fnv::new();
    let b = volume.bounds;
    for v in [b.min, b.max] {
        v.to_array().iter().for_each(|&x| h.f32(x));
    }
    let n = 16;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let t = (Vec3::new(x as f32, y as f32, z as f32) + 0.5) / n as f32;
                let p = b.min + (b.max - b.min) * t;
                let mp = volume.medium.sample_point::<Rgb>(p, &());
                h.f32(mp.sigma_a.x);
                h.f32(mp.sigma_s.x);
                h.f32(mp.le.x);
            }
        }
    }
    // The phase function: an isotropic graph's scalars mean nothing in an anisotropic medium,
    // nor one g's coefficients at another.
    h.f32(volume.medium.g);
    for light in &volume.lights {
        h.bytes(format!("{light:?}").as_bytes());
    }
    // Surfaces beside the medium shadow it and send light into it.
    let s = &volume.scene.surfaces;
    let b = s.bounds();
    for v in [b.min, b.max] {
        v.to_array().iter().for_each(|&x| h.f32(x));
    }
    h.bytes(&(s.top.as_ref().map_or(0, |t| t.primitives().len()) as u64).to_le_bytes());
    h.finish()
}

/// A hash of a configuration.
pub fn config_hash(config: &GraphConfig) -> u64 {
    let mut h = Fnv::new();
    h.bytes(format!("{config:?}").as_bytes());
    h.finish()
}

impl GraphFile {
    /// Writes the file.
    pub fn write(&self, path: &Path) -> Result<()> {
        let n = self.positions.len();
        let mut out = Vec::with_capacity(64 + n * (16 + 4 * self.radiance.len()));
        KIND.write_header(Header { scene_hash: self.scene_hash, settings_hash: self.config_hash }, &mut out);
        out.extend_from_slice(&self.bounces.to_le_bytes());
        out.extend_from_slice(&self.bounces_done.to_le_bytes());
        out.extend_from_slice(&self.node_radius.to_le_bytes());
        out.extend_from_slice(&(self.radiance.len() as u32).to_le_bytes());
        out.extend_from_slice(&self.coefficients.to_le_bytes());
        out.extend_from_slice(&(n as u64).to_le_bytes());
        for p in &self.positions {
            p.to_array().iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        }
        self.ranges.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        for l in &self.radiance {
            l.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        }
        write_file(path, &out)
    }

    /// Reads a file; `expected_scene` refuses a graph built for another scene.
    pub fn read(path: &Path, expected_scene: Option<u64>) -> Result<GraphFile> {
        let bytes = read_file(path)?;
        let bad = |what: &str| Error::malformed(path, format!("not a nimbus graph file ({what})"));
        if !bytes.starts_with(KIND.magic)
            && (bytes.starts_with(b"free")
                || bytes.starts_with(b"basic")
                || bytes.first().is_some_and(u8::is_ascii_digit))
        {
            return Err(Error::Unsupported(format!(
                "{}: a text graph file (the thesis's graph_maker writes those); nimbus reads graphs built by `nimbus graph build`",
                path.display()
            )));
        }
        // Any config: the graph's builder chose it, and rendering reads none.
        let (header, body) = KIND.read_header(&bytes, path, expected_scene, None)?;
        let (scene_hash, config_hash) = (header.scene_hash, header.settings_hash);
        let mut r = Reader { b: body, at: 0 };
        let fields = (|| Some((r.u32()?, r.u32()?, r.f32()?, r.u32()?, r.u32()?, r.u64()?)))();
        let (bounces, bounces_done, node_radius, lights, coefficients, n) =
            fields.ok_or_else(|| bad("truncated header"))?;
        if coefficients != 1 && coefficients as usize != super::sh::COEFFS {
            return Err(bad(&format!("{coefficients} values per node")));
        }
        let n = usize::try_from(n).map_err(|_| bad("node count"))?;
        let per_node = 16 + 4 * lights as usize * coefficients as usize;
        let need = n.checked_mul(per_node).ok_or_else(|| bad("node count"))?;
        if body.len() - r.at != need {
            return Err(bad(&format!("{} bytes of node data, {n} nodes need {need}", body.len() - r.at)));
        }
        let mut floats = |k: usize| (0..k).map(|_| r.f32().expect("length checked")).collect::<Vec<f32>>();
        let p = floats(3 * n);
        let positions = p.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
        let ranges = floats(n);
        let radiance = (0..lights).map(|_| floats(n * coefficients as usize)).collect::<Vec<_>>();
        let all_finite = ranges.iter().chain(radiance.iter().flatten()).chain(p.iter()).all(|v| v.is_finite());
        if !all_finite {
            return Err(bad("NaN or infinite values"));
        }
        Ok(GraphFile {
            scene_hash,
            config_hash,
            bounces,
            bounces_done,
            node_radius,
            coefficients,
            positions,
            ranges,
            radiance,
        })
    }
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, k: usize) -> Option<&[u8]> {
        let s = self.b.get(self.at..self.at + k)?;
        self.at += k;
        Some(s)
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    fn f32(&mut self) -> Option<f32> {
        Some(f32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> GraphFile {
        GraphFile {
            scene_hash: 42,
            config_hash: 7,
            bounces: 9,
            bounces_done: 9,
            node_radius: 0.5,
            coefficients: 1,
            positions: vec![Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)],
            ranges: vec![0.6, 0.7],
            radiance: vec![vec![0.1, 0.2]],
        }
    }

    /// Directional coefficients round-trip; a count that is neither 1 nor theirs is refused.
    #[test]
    fn directional_radiance_round_trips() {
        let dir = std::env::temp_dir().join(format!("nimbus-graphfile-sh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("g.graph");
        let k = crate::integrators::radiancegraph::sh::COEFFS;
        let sh = GraphFile {
            coefficients: k as u32,
            radiance: vec![(0..2 * k).map(|i| i as f32).collect(), vec![0.5; 2 * k]],
            ..sample()
        };
        sh.write(&f).unwrap();
        let back = GraphFile::read(&f, None);
        GraphFile { coefficients: 3, radiance: vec![vec![0.0; 6]], ..sample() }.write(&f).unwrap();
        let odd = GraphFile::read(&f, None);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(back.unwrap(), sh);
        assert!(odd.unwrap_err().to_string().contains("3 values per node"));
    }

    #[test]
    fn round_trip_and_refusals() {
        let dir = std::env::temp_dir().join(format!("nimbus-graphfile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("g.graph");
        sample().write(&f).unwrap();
        let back = GraphFile::read(&f, Some(42));
        let other = GraphFile::read(&f, Some(43));
        let mut bytes = std::fs::read(&f).unwrap();
        bytes[8] = 99;
        std::fs::write(&f, &bytes).unwrap();
        let version = GraphFile::read(&f, None);
        std::fs::write(&f, b"free 1.0\n").unwrap();
        let text = GraphFile::read(&f, None);
        let mut truncated = {
            let mut v = Vec::new();
            sample().write(&dir.join("t.graph")).unwrap();
            v.extend(std::fs::read(dir.join("t.graph")).unwrap());
            v
        };
        truncated.pop();
        std::fs::write(&f, &truncated).unwrap();
        let short = GraphFile::read(&f, None);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(back.unwrap(), sample());
        assert!(other.unwrap_err().to_string().contains("built for another scene"));
        assert!(version.unwrap_err().to_string().contains("graph format version 99, this nimbus reads version 2"));
        assert!(text.unwrap_err().to_string().contains("a text graph file"));
        assert!(short.unwrap_err().to_string().contains("not a nimbus graph file"));
    }
}
