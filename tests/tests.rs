//! End-to-end tests of the `nimbus` binary and library.

mod architecture;
mod bench;
mod camera;
mod check;
mod checksums;
mod cluster;
mod common;
mod compare;
mod coverage;
mod film;
mod guided;
mod lights;
mod materials;
mod media;
mod motion;
mod pathgraph;
mod pbrt_v4_parity;
mod radiancegraph;
mod render;
mod render_cli;
mod robustness;
mod shapes;
mod simplevolpath;
mod stress;
mod suite;
mod textures;
