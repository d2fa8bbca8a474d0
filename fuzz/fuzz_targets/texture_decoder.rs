//! The ray tracer's texture decoders (BMP, PNG, JPEG, and whatever else the content looks like)
//! on any bytes, behind the same header checks, image::Limits and memory budget as a scene's
//! textures.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raytracer::MemoryBudget;
use raytracer::texture::Texture;

fuzz_target!(|bytes: &[u8]| {
    let budget = MemoryBudget::new(256 << 20);
    if let Ok(texture) = Texture::from_bytes(bytes, "fuzz.img", &budget) {
        let _ = texture.sample(0.3, 0.7);
    }
});
