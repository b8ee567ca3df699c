//! The radiance-graph method of van den Hurk's thesis (2026): light paths grouped into a graph
//! of volume nodes, direct light per node, transport through the graph by a Neumann series,
//! and rendering from the nodes' radiance. See this folder's README for the map from the
//! thesis's sections and equations to files.
//!
//! Under construction: the parts here are complete and tested, but the method has no name in
//! the CLI until graph building and rendering land.

pub mod config;
pub mod search_range;
pub mod transport;
