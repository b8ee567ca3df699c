//! The channels light is carried in. nimbus transports either linear RGB in the film's
//! color space ([`Rgb`]) or pbrt-v4's sampled spectra (four wavelengths per path), chosen per
//! scene; everything that multiplies light — BSDFs, media, lights, the path loop — is
//! written once, generic over [`Channels`], and monomorphised for each representation.

mod channels;

pub use channels::{Channels, pack_voxel, rgb_spectrum};

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
