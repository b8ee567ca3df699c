//! Tests of the NanoVDB and OpenVDB readers against the fixtures of
//! `tests/fixtures/vdb/generate.py` (the expected numbers are what that script printed) and
//! against the vdb-cloud reference scene's grid, stored in both formats.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{DVec3, IVec3, Vec3};

use super::{GridError, NanoVdbFile, OpenVdbFile, SparseGrid};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/vdb").join(name)
}

fn reference_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/pbrt-v4-references/scenes").join(name)
}

fn nano(name: &str, grid: &str) -> Result<SparseGrid, GridError> {
    NanoVdbFile::open(fixture(name))?.read_grid(grid)
}

fn open(name: &str, grid: &str) -> Result<SparseGrid, GridError> {
    OpenVdbFile::open(fixture(name))?.read_grid(grid)
}

/// A scratch directory for files made from fixtures.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nimbus-vdb-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `(ijk, value, active)` as generate.py prints them; values must match bit for bit.
type Probe = ([i32; 3], f32, bool);

fn assert_probes(grid: &SparseGrid, probes: &[Probe], what: &str) {
    for &(ijk, value, _) in probes {
        let got = grid.value(IVec3::from(ijk));
        assert_eq!(got.to_bits(), value.to_bits(), "{what} at {ijk:?}: {got} vs {value}");
    }
}

/// `(index point, world point)` as generate.py prints them.
fn assert_map(grid: &SparseGrid, points: &[([f64; 3], [f64; 3])], what: &str) {
    for &(i, w) in points {
        let got = grid.world_from_index_f64().transform_point3(DVec3::from(i));
        assert!((got - DVec3::from(w)).length() < 1e-12, "{what}: {i:?} -> {got} vs {w:?}");
        let back = grid.index_from_world_f64().transform_point3(DVec3::from(w));
        assert!((back - DVec3::from(i)).length() < 1e-9, "{what}: inverse at {w:?}");
    }
}

/// Every voxel of both grids' bounding boxes (plus a margin) is the same, as are the bounds
/// and transform.
fn assert_same_grid(a: &SparseGrid, b: &SparseGrid, what: &str) {
    assert_eq!(a.index_bounds(), b.index_bounds(), "{what}: index bounds");
    assert_eq!(a.world_from_index_f64(), b.world_from_index_f64(), "{what}: transform");
    let (wa, wb) = (a.world_bounds(), b.world_bounds());
    assert!(
        (wa.min - wb.min).abs().max_element() < 1e-6 && (wa.max - wb.max).abs().max_element() < 1e-6,
        "{what}: world bounds {wa:?} vs {wb:?}"
    );
    let (lo, hi) = a.index_bounds();
    for x in lo.x - 2..=hi.x + 2 {
        for y in lo.y - 2..=hi.y + 2 {
            for z in lo.z - 2..=hi.z + 2 {
                let p = IVec3::new(x, y, z);
                assert_eq!(a.value(p).to_bits(), b.value(p).to_bits(), "{what}: voxel {p}");
            }
        }
    }
}

const FOG_DENSITY: [Probe; 11] = [
    ([3, 1, 2], 0.7119281, true),
    ([10, 7, 8], 0.58599645, true),
    ([20, 14, 12], 0.6858179, true),
    ([7, 0, 5], 0.0, false),
    ([5, 5, 5], 0.3, false),
    ([8, 8, 8], 0.5750692, true),
    ([24, 8, 0], 0.75, true),
    ([31, 15, 7], 0.75, true),
    ([23, 8, 0], 0.0, false),
    ([0, 0, 0], 0.0, false),
    ([-1, -5, 3], 0.0, false),
];
const FOG_MAP: [([f64; 3], [f64; 3]); 3] = [
    ([0.0, 0.0, 0.0], [1.5, -2.0, 0.75]),
    ([1.0, 2.0, 3.0], [1.75, -1.5, 1.5]),
    ([-4.5, 0.25, 7.0], [0.375, -1.9375, 2.5]),
];
const AFFINE_MAP: [([f64; 3], [f64; 3]); 3] = [
    ([0.0, 0.0, 0.0], [1.0, 2.0, 3.0]),
    ([1.0, 2.0, 3.0], [2.1, 2.6, 9.1]),
    ([-4.5, 0.25, 7.0], [0.15000000000000013, 1.6125, 17.0125]),
];
const FOG_BOUNDS: (IVec3, IVec3) = (IVec3::new(3, 1, 0), IVec3::new(31, 15, 12));
const TEMPERATURE: [Probe; 3] = [([2, 2, 2], 322.0, true), ([5, 4, 3], 445.0, true), ([1, 2, 2], 0.0, false)];

#[test]
fn vdb_fog_volume_values_transform_and_bounds_from_both_formats() {
    for (what, grid) in [("fog.vdb", open("fog.vdb", "density")), ("fog.nvdb", nano("fog.nvdb", "density"))] {
        let grid = grid.unwrap();
        assert_probes(&grid, &FOG_DENSITY, what);
        assert_map(&grid, &FOG_MAP, what);
        assert_eq!(grid.index_bounds(), FOG_BOUNDS, "{what}");
        // World bounds: the active voxels' cells [min, max + 1] under the transform.
        let b = grid.world_bounds();
        assert_eq!((b.min, b.max), (Vec3::new(2.25, -1.75, 0.75), Vec3::new(9.5, 2.0, 4.0)), "{what}");
        // Inside the 8³ tile, sampling anywhere gives the tile's value.
        assert_eq!(grid.sample(Vec3::new(26.3, 11.7, 3.5)), 0.75);
    }
    assert_same_grid(&open("fog.vdb", "density").unwrap(), &nano("fog.nvdb", "density").unwrap(), "fog");
}

#[test]
fn vdb_grids_are_selected_by_name_and_unknown_class_is_accepted() {
    for (what, grid) in [("fog.vdb", open("fog.vdb", "temperature")), ("fog.nvdb", nano("fog.nvdb", "temperature"))] {
        let grid = grid.unwrap();
        assert_probes(&grid, &TEMPERATURE, what);
        assert_map(&grid, &[([1.0, 2.0, 3.0], [0.5, 1.0, 1.5]), ([-4.5, 0.25, 7.0], [-2.25, 0.125, 3.5])], what);
        assert_eq!(grid.index_bounds(), (IVec3::splat(2), IVec3::splat(5)));
    }
    let file = OpenVdbFile::open(fixture("fog.vdb")).unwrap();
    assert_eq!(file.grid_names(), ["density", "temperature", "density_moved"]);
    assert!(file.has_grid("temperature") && !file.has_grid("velocity"));
    let file = NanoVdbFile::open(fixture("fog.nvdb")).unwrap();
    assert_eq!(file.grid_names(), ["density", "density_moved", "temperature"]);
}

#[test]
fn vdb_instance_grid_shares_the_tree_with_its_own_transform() {
    // "density_moved" is written as an instance of "density": no tree of its own.
    let moved = open("fog.vdb", "density_moved").unwrap();
    assert_probes(&moved, &FOG_DENSITY, "density_moved");
    assert_map(&moved, &[([1.0, 2.0, 3.0], [2.0, 4.0, 6.0]), ([-4.5, 0.25, 7.0], [-9.0, 0.5, 14.0])], "density_moved");
    assert_same_grid(&moved, &nano("fog.nvdb", "density_moved").unwrap(), "density_moved");
}

#[test]
fn vdb_quantised_nanovdb_grids_decode_as_nanovdb_does() {
    // Values printed by converting each file back to OpenVDB with nanovdb_convert.
    let expected: [(&str, [f32; 5]); 4] = [
        ("fog_fp4.nvdb", [0.7058158, 0.5760332, 0.6837217, 0.32576114, 0.56684184]),
        ("fog_fp8.nvdb", [0.7122033, 0.5852743, 0.6870733, 0.30021125, 0.5735105]),
        ("fog_fp16.nvdb", [0.71192986, 0.58599347, 0.68582135, 0.29999998, 0.57506746]),
        ("fog_fpn.nvdb", [0.8144029, 0.5236665, 0.56976813, 0.27146763, 0.5668418]),
    ];
    let ijk = [[3, 1, 2], [10, 7, 8], [20, 14, 12], [5, 5, 5], [8, 8, 8]];
    for (name, values) in expected {
        let grid = nano(name, "density").unwrap();
        let probes: Vec<Probe> = ijk.iter().zip(values).map(|(&p, v)| (p, v, true)).collect();
        assert_probes(&grid, &probes, name);
        // Tiles and background are not quantised.
        assert_probes(&grid, &FOG_DENSITY[6..], name);
        assert_eq!(grid.index_bounds(), FOG_BOUNDS, "{name}");
    }
}

#[test]
fn vdb_half_float_grids_compressed_or_not() {
    let probes: [Probe; 4] = [
        ([3, 1, 2], 0.71191406, true),
        ([12, 9, 7], 0.59521484, true),
        ([8, 4, 5], 0.66748047, true),
        ([2, 1, 2], 0.0, false),
    ];
    // half.vdb is Blosc-compressed, which vdb-rs alone fails on; half_active.vdb is not.
    for name in ["half.vdb", "half_active.vdb"] {
        let grid = open(name, "density").unwrap();
        assert_probes(&grid, &probes, name);
        assert_eq!(grid.index_bounds(), (IVec3::new(3, 1, 2), IVec3::new(12, 9, 7)), "{name}");
        assert_map(&grid, &[([1.0, 2.0, 3.0], [0.5, 1.0, 1.5])], name);
    }
}

#[test]
fn vdb_scale_and_affine_maps_that_vdb_rs_panics_on_are_read() {
    let probes: [Probe; 3] = [([1, 2, 3], 0.59804803, true), ([6, 6, 6], 0.6482203, true), ([0, 2, 3], 0.0, false)];
    let scale = open("scalemap.vdb", "density").unwrap();
    assert_probes(&scale, &probes, "scalemap.vdb");
    assert_map(
        &scale,
        &[([1.0, 2.0, 3.0], [0.5, 0.5, 6.0]), ([-4.5, 0.25, 7.0], [-2.25, 0.0625, 14.0])],
        "scalemap.vdb",
    );
    let affine = open("affine.vdb", "density").unwrap();
    assert_probes(&affine, &probes, "affine.vdb");
    assert_map(&affine, &AFFINE_MAP, "affine.vdb");
}

#[test]
fn vdb_nanovdb_affine_map_matches_its_source_vdb() {
    // NanoVDB maps world = M · index + t with M row-major; nanovdb_convert stores OpenVDB's
    // row-vector matrix transposed accordingly. (Its reverse conversion, .nvdb -> .vdb, in
    // 32.4.2 transposes it back wrongly, which is why generate.py prints no .nvdb transform.)
    let affine = nano("affine.nvdb", "density").unwrap();
    assert_map(&affine, &AFFINE_MAP, "affine.nvdb");
    assert_same_grid(&affine, &open("affine.vdb", "density").unwrap(), "affine");
}

#[test]
fn vdb_unsupported_grids_are_clear_errors() {
    let message = |r: Result<SparseGrid, GridError>| r.unwrap_err().to_string();
    // vdb-rs would read a vec3 grid as empty.
    let e = open("vec3.vdb", "velocity").unwrap_err();
    assert!(matches!(e, GridError::UnsupportedValueType { .. }), "{e}");
    assert!(e.to_string().contains("vec3s values; only float (scalar) grids"), "{e}");
    let e = message(nano("vec3.nvdb", "velocity"));
    assert!(e.contains("vec3f values; only float"), "{e}");
    for e in [open("empty.vdb", "density").unwrap_err(), nano("empty.nvdb", "density").unwrap_err()] {
        assert!(matches!(e, GridError::EmptyGrid { .. }), "{e}");
        assert!(e.to_string().contains("grid \"density\" has no active voxels"), "{e}");
    }
    for e in [message(open("levelset.vdb", "density")), message(nano("levelset.nvdb", "density"))] {
        assert!(e.contains("not a fog volume") && e.contains("FogVolume"), "{e}");
    }
    let e = message(nano("fog_blosc.nvdb", "density"));
    assert!(e.contains("BLOSC compression is not supported") && e.contains("-z/--zip"), "{e}");
    for e in [message(open("fog.vdb", "smoke")), message(nano("fog.nvdb", "smoke"))] {
        assert!(e.contains("no grid named \"smoke\""), "{e}");
        assert!(e.contains("density (float)") && e.contains("temperature (float)"), "{e}");
    }
    // Each format's reader names the other format.
    let e = NanoVdbFile::open(fixture("fog.vdb")).unwrap_err().to_string();
    assert!(e.contains("OpenVDB file") && e.contains("\"vdb\" medium"), "{e}");
    let e = OpenVdbFile::open(fixture("fog.nvdb")).unwrap_err().to_string();
    assert!(e.contains("NanoVDB file") && e.contains("\"nanovdb\" medium"), "{e}");
    let e = NanoVdbFile::open(fixture("missing.nvdb")).unwrap_err();
    assert!(matches!(e, GridError::Io { .. }) && e.to_string().contains("missing.nvdb"), "{e}");
}

/// One segment of a .nvdb file: header, metadata records (with names), grid buffers.
struct Segment {
    header: Vec<u8>,
    metas: Vec<Vec<u8>>,
    grids: Vec<Vec<u8>>,
}

/// The segments of a Zip-coded .nvdb, decompressed.
fn unzip_nanovdb(path: &Path) -> Vec<Segment> {
    use std::io::Read;
    let bytes = std::fs::read(path).unwrap();
    let mut segments = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let header = bytes[at..at + 16].to_vec();
        assert_eq!(u16::from_le_bytes([header[14], header[15]]), 1, "a Zip-coded fixture");
        let count = u16::from_le_bytes([header[12], header[13]]) as usize;
        at += 16;
        let mut metas = Vec::new();
        for _ in 0..count {
            let name_size = u32::from_le_bytes(bytes[at + 136..at + 140].try_into().unwrap()) as usize;
            metas.push(bytes[at..at + 176 + name_size].to_vec());
            at += 176 + name_size;
        }
        let mut grids = Vec::new();
        for _ in 0..count {
            let n = u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
            let mut grid = Vec::new();
            flate2::read::ZlibDecoder::new(&bytes[at + 8..at + 8 + n]).read_to_end(&mut grid).unwrap();
            grids.push(grid);
            at += 8 + n;
        }
        segments.push(Segment { header, metas, grids });
    }
    segments
}

/// The segments written back with codec NONE (file size = grid size).
fn uncompressed(segments: &[Segment]) -> Vec<u8> {
    let mut out = Vec::new();
    for s in segments {
        let mut header = s.header.clone();
        header[14] = 0;
        out.extend_from_slice(&header);
        for (meta, grid) in s.metas.iter().zip(&s.grids) {
            let mut meta = meta.clone();
            meta[8..16].copy_from_slice(&(grid.len() as u64).to_le_bytes());
            out.extend_from_slice(&meta);
        }
        for grid in &s.grids {
            out.extend_from_slice(grid);
        }
    }
    out
}

#[test]
fn vdb_nanovdb_uncompressed_and_raw_buffers_read_like_zip() {
    let dir = scratch("codecs");
    let segments = unzip_nanovdb(&fixture("fog.nvdb"));
    assert_eq!(segments.len(), 3, "nanovdb_convert writes a segment per grid");
    std::fs::write(dir.join("none.nvdb"), uncompressed(&segments)).unwrap();
    // A raw buffer of grids, no segment header (NanoVDB 32.6+ can write these).
    let raw: Vec<u8> = segments.iter().flat_map(|s| s.grids.concat()).collect();
    std::fs::write(dir.join("raw.nvdb"), raw).unwrap();
    let zip = nano("fog.nvdb", "density").unwrap();
    for file in ["none.nvdb", "raw.nvdb"] {
        let f = NanoVdbFile::open(dir.join(file)).unwrap();
        assert_eq!(f.grid_names(), ["density", "density_moved", "temperature"], "{file}");
        assert_same_grid(&f.read_grid("density").unwrap(), &zip, file);
        assert_probes(&f.read_grid("temperature").unwrap(), &TEMPERATURE, file);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vdb_corrupt_nanovdb_files_are_errors_not_panics() {
    let dir = scratch("corrupt");
    let segments = unzip_nanovdb(&fixture("fog.nvdb"));
    let file = uncompressed(&segments[..1]);
    let grid_at = 16 + segments[0].metas[0].len();
    let grid_len = segments[0].grids[0].len();
    // Truncations anywhere: the grid list or the grid must fail cleanly.
    for cut in [10, 100, grid_at + 100, grid_at + 800, file.len() - 1] {
        let path = dir.join("cut.nvdb");
        std::fs::write(&path, &file[..cut]).unwrap();
        let read = NanoVdbFile::open(&path).and_then(|f| f.read_grid("density"));
        assert!(read.is_err(), "cut at {cut}");
    }
    // Overwritten bytes in the tree: any outcome but a panic (a value change reads fine).
    let mut n = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..300 {
        n ^= n << 13;
        n ^= n >> 7;
        n ^= n << 17;
        let mut bad = file.clone();
        let at = grid_at + 672 + (n as usize % (grid_len - 672));
        bad[at] ^= (n >> 32) as u8 | 1;
        let path = dir.join("bad.nvdb");
        std::fs::write(&path, &bad).unwrap();
        let _ = NanoVdbFile::open(&path).and_then(|f| f.read_grid("density"));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vdb_truncated_openvdb_file_is_an_error() {
    let dir = scratch("vdbcut");
    let bytes = std::fs::read(fixture("half.vdb")).unwrap();
    for cut in [6, 200, bytes.len() / 2, bytes.len() - 3] {
        let path = dir.join("cut.vdb");
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let read = OpenVdbFile::open(&path).and_then(|f| f.read_grid("density"));
        assert!(read.is_err(), "cut at {cut}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vdb_rs_panics_become_errors() {
    // vdb-rs asserts that a file has grid offsets; a file claiming none makes it panic.
    let dir = scratch("panic");
    let mut bytes = std::fs::read(fixture("half.vdb")).unwrap();
    assert_eq!(bytes[20], 1, "the has-grid-offsets flag follows magic and versions");
    bytes[20] = 0;
    let path = dir.join("no-offsets.vdb");
    std::fs::write(&path, &bytes).unwrap();
    let e = OpenVdbFile::open(&path).unwrap_err().to_string();
    assert!(e.contains("vdb-rs failed reading the header") && e.contains("has_grid_offsets"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vdb_cloud_nanovdb_and_openvdb_files_hold_the_same_grid() {
    let start = Instant::now();
    let nvdb = NanoVdbFile::open(reference_scene("vdb-cloud.nvdb")).and_then(|f| f.read_grid("density")).unwrap();
    let nvdb_time = start.elapsed();
    let vdb = OpenVdbFile::open(reference_scene("vdb-cloud.vdb")).and_then(|f| f.read_grid("density")).unwrap();
    // Well under a second even unoptimised (release: milliseconds).
    println!("vdb-cloud.nvdb read in {nvdb_time:?}, {} bytes", nvdb.memory_bytes());
    assert!(nvdb_time.as_secs_f64() < 1.0, "reading vdb-cloud.nvdb took {nvdb_time:?}");
    assert_eq!(nvdb.index_bounds(), (IVec3::new(-15, -21, -24), IVec3::new(22, 16, 21)));
    assert_same_grid(&nvdb, &vdb, "vdb-cloud");
    // pbrt-v4 bounds the medium by the file's world box: the cells of the active voxels.
    let b = nvdb.world_bounds();
    assert_eq!(b.min, Vec3::new(-15.0, -21.0, -24.0) * 0.03125);
    assert_eq!(b.max, Vec3::new(23.0, 17.0, 22.0) * 0.03125);
    // Samples and majorants agree too (same data, same code, so bit for bit).
    let mut n = 1u64;
    let mut next = || {
        n = n.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (n >> 40) as f32 / (1u64 << 24) as f32
    };
    for _ in 0..2000 {
        let p = Vec3::new(-0.5 + next(), -0.7 + 1.3 * next(), -0.8 + 1.6 * next());
        let i = nvdb.index_from_world().transform_point3(p);
        assert_eq!(nvdb.sample(i).to_bits(), vdb.sample(i).to_bits(), "{p}");
    }
    for _ in 0..200 {
        let lo = IVec3::new((next() * 50.0) as i32 - 20, (next() * 50.0) as i32 - 25, (next() * 55.0) as i32 - 28);
        let hi = lo + IVec3::new((next() * 12.0) as i32, (next() * 12.0) as i32, (next() * 12.0) as i32);
        let m = nvdb.max_over(lo, hi);
        assert_eq!(m, vdb.max_over(lo, hi));
        let mut brute = f32::NEG_INFINITY;
        for x in lo.x..=hi.x {
            for y in lo.y..=hi.y {
                for z in lo.z..=hi.z {
                    brute = brute.max(nvdb.value(IVec3::new(x, y, z)));
                }
            }
        }
        assert_eq!(m, brute, "{lo} ..= {hi}");
    }
}
