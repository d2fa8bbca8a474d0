//! Uploading images as mipmapped textures, samplers, and the depth buffer.

use image::RgbaImage;
use image::imageops::{self, FilterType};

use super::RenderError;

/// Format of every colour texture: 8-bit RGBA, values used as stored (no sRGB decoding), as the
/// course's OpenGL renderer did; the ADD_SIGNED combination works on these stored values.
pub const TEXTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Format of the depth buffer.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The image and its successively halved copies down to 1x1 (a full mip chain), each level
/// filtered from the previous one.
pub fn mip_chain(image: &RgbaImage) -> Vec<RgbaImage> {
    let mut levels = vec![image.clone()];
    while let Some(last) = levels.last() {
        let (width, height) = last.dimensions();
        if width == 1 && height == 1 {
            break;
        }
        let next = imageops::resize(last, (width / 2).max(1), (height / 2).max(1), FilterType::Triangle);
        levels.push(next);
    }
    levels
}

/// Uploads `layers` (all the same size) as one mipmapped 2-D texture array, or a plain 2-D
/// texture when there is one layer. `what` names the texture in errors.
pub fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    what: &str,
    layers: &[&RgbaImage],
) -> Result<wgpu::Texture, RenderError> {
    let (width, height) = layers.first().map_or((0, 0), |image| image.dimensions());
    let max = device.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(RenderError::TextureSize { what: what.to_string(), width, height, max });
    }
    let chains: Vec<Vec<RgbaImage>> = layers.iter().map(|image| mip_chain(image)).collect();
    let mip_level_count = chains[0].len() as u32;
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(what),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: layers.len() as u32 },
        mip_level_count,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: TEXTURE_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (layer, chain) in chains.iter().enumerate() {
        for (level, image) in chain.iter().enumerate() {
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: level as u32,
                    origin: wgpu::Origin3d { x: 0, y: 0, z: layer as u32 },
                    aspect: wgpu::TextureAspect::All,
                },
                image.as_raw(),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * image.width()),
                    rows_per_image: Some(image.height()),
                },
                wgpu::Extent3d { width: image.width(), height: image.height(), depth_or_array_layers: 1 },
            );
        }
    }
    Ok(texture)
}

/// A trilinear sampler that clamps (`repeat = false`) or repeats texture coordinates.
pub fn sampler(device: &wgpu::Device, repeat: bool) -> wgpu::Sampler {
    let address = if repeat { wgpu::AddressMode::Repeat } else { wgpu::AddressMode::ClampToEdge };
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(if repeat { "repeat" } else { "clamp" }),
        address_mode_u: address,
        address_mode_v: address,
        address_mode_w: address,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    })
}

/// A sampler that repeats texture coordinates and filters bilinearly within the nearest mip
/// level, without blending two levels as [`sampler`] does: for the ground's material noise,
/// whose grain hides where the level changes. On lavapipe, which runs the shaders on the CPU, a
/// sample costs about half a trilinear one.
pub fn nearest_level_sampler(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("repeat, nearest level"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        address_mode_w: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Nearest,
        ..Default::default()
    })
}

/// A depth buffer matching a colour target's size.
#[derive(Debug)]
pub struct DepthBuffer {
    view: wgpu::TextureView,
    size: (u32, u32),
}

impl DepthBuffer {
    /// A depth buffer of `size` (width, height) pixels.
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("depth"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        Self { view: texture.create_view(&wgpu::TextureViewDescriptor::default()), size }
    }

    /// The buffer's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The view to attach to a render pass.
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mip_chain_halves_down_to_one_texel() {
        let image = RgbaImage::from_pixel(12, 5, image::Rgba([10, 20, 30, 255]));
        let sizes: Vec<_> = mip_chain(&image).iter().map(RgbaImage::dimensions).collect();
        assert_eq!(sizes, vec![(12, 5), (6, 2), (3, 1), (1, 1)]);
        // A flat image stays flat at every level.
        assert!(mip_chain(&image).iter().all(|level| level.pixels().all(|p| p.0 == [10, 20, 30, 255])));
    }

    #[test]
    fn mip_chain_averages() {
        let image = RgbaImage::from_fn(2, 2, |x, _| image::Rgba([if x == 0 { 0 } else { 200 }, 0, 0, 255]));
        let chain = mip_chain(&image);
        assert_eq!(chain.len(), 2);
        let red = chain[1].get_pixel(0, 0).0[0];
        assert!((95..=105).contains(&red), "{red}");
    }
}
