//! The film side of rendering: pixel reconstruction filters.

pub mod filter;
