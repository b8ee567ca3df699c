//! The film side of rendering: its settings, pixel reconstruction filters, and how a sample
//! reaches the film in either representation of light.

pub mod channels;
pub mod filter;
pub mod filter_settings;
pub mod settings;
