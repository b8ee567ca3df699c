//! The film side of rendering: pixel reconstruction filters.

pub mod filter;
pub mod filter_settings;
pub mod settings;
