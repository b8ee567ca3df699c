//! Linear RGB: the film's color space values and what they are measured by. The spectral
//! alternative lives in [`crate::spectra`]; [`crate::channels`] makes the two one interface.

use glam::Vec3;

/// Linear RGB radiance, reflectance or throughput. Arithmetic is per channel.
pub type Rgb = Vec3;

/// Luminance (Y) of linear sRGB / Rec. 709 primaries.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    0.212_672_9 * c.x + 0.715_152_2 * c.y + 0.072_175 * c.z
}

/// Average of the three channels.
#[inline]
pub fn average(c: Rgb) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// True when all channels are equal (a gray, spectrally constant quantity).
#[inline]
pub fn is_gray(c: Rgb) -> bool {
    c.x == c.y && c.y == c.z
}
