//! The modern look's shared lighting (group 2 of its shaders, `lighting.wgsl`): the sun (or the
//! moon), the sky's light, the fog, the water's parameters, the sky-view table of the atmosphere
//! (the sky's and the fog's colour, `world::atmosphere`) and the shadow map.

use bytemuck::{Pod, Zeroable};
use glam::{DVec2, Mat4, Vec3};

use super::pipeline::{Binding, bind_group};
use super::texture::sampler;
use crate::config::SceneConfig;
use crate::settings::{ReflectionQuality, Settings};
use crate::world::atmosphere::{Atmosphere, SKY_VIEW_HEIGHT, SKY_VIEW_WIDTH, SkyLight};

/// Side of the shadow map, in texels.
pub const SHADOW_MAP_SIZE: u32 = 2048;

/// Format of the shadow map.
pub const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The WGSL struct `Scene`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct SceneUniforms {
    sun_direction: [f32; 4],
    sun_colour: [f32; 4],
    sky_light: [f32; 4],
    fog: [f32; 4],
    water_colour: [f32; 4],
    waves: [f32; 4],
    wave_params: [f32; 4],
    water_flags: [f32; 4],
    shadow_matrix: [[f32; 4]; 4],
    sky_box: [f32; 4],
    sky_sun: [f32; 4],
    sun_disc: [f32; 4],
    ground: [f32; 4],
    ground_scale: [f32; 4],
}

/// What the scene uniforms are computed from, besides the settings.
#[derive(Debug, Clone, Copy)]
pub struct SceneInputs {
    /// Seconds since the scene started.
    pub time_seconds: f64,
    /// The frame's size in pixels.
    pub frame_size: (u32, u32),
    /// World to the shadow map's clip space.
    pub shadow_matrix: Mat4,
    /// The atmosphere's lights for the sun of the settings.
    pub sky: SkySummary,
}

/// What the scene uniforms take of a [`SkyLight`] (all but its table).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkySummary {
    /// Toward the sun (unit).
    pub sun_direction: Vec3,
    /// The sun's light, linear.
    pub sun_colour: Vec3,
    /// Toward the light that casts shadows (the sun, or the moon at night).
    pub key_direction: Vec3,
    /// That light's colour, linear.
    pub key_colour: Vec3,
    /// The sky dome's light, linear (before the ambient strength).
    pub sky_light: Vec3,
    /// 0 by day to 1 at night.
    pub night: f32,
    /// How bright the scene is against a sunny day (0.05 to 1).
    pub daylight: f32,
    /// The sky's mean colour along the horizon (stored values, 0..=1): where no land or water
    /// is drawn below it, the frame shows this.
    pub horizon: Vec3,
}

impl From<&SkyLight> for SkySummary {
    fn from(sky: &SkyLight) -> Self {
        Self {
            sun_direction: sky.sun_direction,
            sun_colour: sky.sun_colour,
            key_direction: sky.key_direction,
            key_colour: sky.key_colour,
            sky_light: sky.sky_light,
            night: sky.night,
            daylight: sky.daylight,
            horizon: sky.texels[..SKY_VIEW_WIDTH as usize]
                .iter()
                .map(|t| Vec3::new(f32::from(t[0]), f32::from(t[1]), f32::from(t[2])) / 255.0)
                .sum::<Vec3>()
                / SKY_VIEW_WIDTH as f32,
        }
    }
}

impl SceneUniforms {
    /// The uniforms of `settings` for a scene laid out with `config`.
    pub fn new(settings: &Settings, config: &SceneConfig, inputs: &SceneInputs) -> Self {
        let flag = |on: bool| if on { 1.0 } else { 0.0 };
        let sun = &settings.sun;
        let water = &settings.water;
        let sky = &inputs.sky;
        let tint = Vec3::from_array(sun.colour);
        let key_colour = sky.key_colour * tint;
        let sky_light = sky.sky_light * sun.ambient;
        // The sun's disc: its colour through the air, bright enough to saturate (stored values).
        let disc = (sky.sun_colour * tint * 40.0).min(Vec3::ONE).powf(0.5);
        // The waves drift at the course's speed (its water texture's, in world units a second),
        // times the settings' factor; the second map crosses the first at an angle.
        let course_speed = DVec2::new(
            f64::from(config.wave_velocity.x) * f64::from(config.sky_box_size.x / config.water_repeat.x),
            f64::from(config.wave_velocity.y) * f64::from(config.sky_box_size.z / config.water_repeat.y),
        );
        let travel =
            course_speed * f64::from(water.wave_speed) * inputs.time_seconds / f64::from(water.wave_scale);
        let crossing =
            DVec2::new(travel.x * 0.6 - travel.y * 0.8, travel.x * 0.8 + travel.y * 0.6) * 1.37 * 0.8;
        let wrap = |v: f64| v.rem_euclid(1.0) as f32;
        let box_size = config.sky_box_size;
        let ground = &settings.ground;
        // The land's highest point above the water (world units).
        let top = config.height_of_level(255.0).max(1e-3);
        Self {
            sun_direction: sky.key_direction.extend(flag(sun.lighting)).to_array(),
            sun_colour: key_colour.extend(flag(sun.lighting && sun.shadows)).to_array(),
            sky_light: sky_light.extend(0.0).to_array(),
            fog: [
                settings.fog.density,
                settings.fog.height_falloff,
                flag(settings.fog.enabled),
                (inputs.time_seconds.rem_euclid(3600.0)) as f32,
            ],
            water_colour: [water.colour[0], water.colour[1], water.colour[2], water.clarity],
            waves: [wrap(travel.x), wrap(travel.y), wrap(crossing.x), wrap(crossing.y)],
            wave_params: [
                1.0 / water.wave_scale,
                water.wave_strength,
                flag(water.refraction),
                flag(water.glint),
            ],
            water_flags: [
                flag(water.foam),
                flag(water.reflection != ReflectionQuality::Off),
                inputs.frame_size.0 as f32,
                inputs.frame_size.1 as f32,
            ],
            shadow_matrix: inputs.shadow_matrix.to_cols_array_2d(),
            sky_box: [box_size.x / 2.0, box_size.y, box_size.z / 2.0, 1.0 / SHADOW_MAP_SIZE as f32],
            sky_sun: sky.sun_direction.extend(sky.daylight).to_array(),
            sun_disc: disc.extend(sky.night).to_array(),
            ground: [
                flag(ground.materials),
                1.0 - ground.rock_slope_degrees.to_radians().cos(),
                ground.snow_line * top,
                // No shore without a sea.
                if config.sea { ground.sand_line * top } else { -1e4 },
            ],
            ground_scale: [1.0 / (ground.texture_size * config.terrain_length), ground.detail, top, 0.0],
        }
    }
}

/// World to the shadow map's clip space: an orthographic view along the sun's light that covers
/// the box from `min` to `max` (the terrain).
pub fn sun_matrix(sun: Vec3, min: Vec3, max: Vec3) -> Mat4 {
    let centre = (min + max) * 0.5;
    let radius = (max - min).length() * 0.5 + 1.0;
    let toward_sun = if sun.y < 0.02 { Vec3::new(sun.x, 0.02, sun.z).normalize() } else { sun.normalize() };
    let up = if toward_sun.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let view = glam::camera::rh::view::look_to_mat4(centre + toward_sun * radius, -toward_sun, up);
    let corners = (0..8).map(|i| {
        Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    });
    let (mut low, mut high) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for corner in corners {
        let p = view.transform_point3(corner);
        low = low.min(p);
        high = high.max(p);
    }
    // The camera looks down -z: depths are -z.
    glam::camera::rh::proj::directx::orthographic(low.x, high.x, low.y, high.y, -high.z - 0.01, -low.z + 0.01)
        * view
}

/// The shadow map and the lighting bind group (group 2).
#[derive(Debug)]
pub struct Lighting {
    /// The scene uniforms.
    pub buffer: wgpu::Buffer,
    /// The layout of group 2.
    pub layout: wgpu::BindGroupLayout,
    /// Group 2.
    pub group: wgpu::BindGroup,
    /// The shadow map's view, to render into.
    pub shadow_view: wgpu::TextureView,
    /// The atmosphere (its transmittance table).
    atmosphere: Atmosphere,
    /// The sky-view table on the GPU.
    sky_view: wgpu::Texture,
    /// The sun direction and exposure the table was worked out for, and its lights.
    sky: Option<(Vec3, f32, SkySummary)>,
}

impl Lighting {
    /// The lighting resources, with the atmosphere's sky-view table (worked out on the first
    /// [`Lighting::update_sky`]).
    pub fn new(device: &wgpu::Device) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene uniforms"),
            size: size_of::<SceneUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let shadow = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow map"),
            size: wgpu::Extent3d {
                width: SHADOW_MAP_SIZE,
                height: SHADOW_MAP_SIZE,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SHADOW_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let shadow_view = shadow.create_view(&wgpu::TextureViewDescriptor::default());
        let comparison = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow comparison"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let sky_view = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("sky view"),
            size: wgpu::Extent3d { width: SKY_VIEW_WIDTH, height: SKY_VIEW_HEIGHT, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let sky_view_view = sky_view.create_view(&wgpu::TextureViewDescriptor::default());
        let (layout, group) = bind_group(
            device,
            "lighting",
            &[
                Binding::Uniform(&buffer),
                Binding::Texture(&sky_view_view),
                Binding::Sampler(&sampler(device, false)),
                Binding::DepthTexture(&shadow_view),
                Binding::ComparisonSampler(&comparison),
            ],
        );
        Self { buffer, layout, group, shadow_view, atmosphere: Atmosphere::earth(), sky_view, sky: None }
    }

    /// The atmosphere's lights for the sun toward `sun` at `exposure`, working the sky-view
    /// table out again and uploading it only when either changed.
    pub fn update_sky(&mut self, queue: &wgpu::Queue, sun: Vec3, exposure: f32) -> SkySummary {
        if let Some((drawn_sun, drawn_exposure, summary)) = self.sky
            && drawn_sun == sun
            && drawn_exposure == exposure
        {
            return summary;
        }
        let light = self.atmosphere.sky(sun, exposure);
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.sky_view,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&light.texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(SKY_VIEW_WIDTH * 4),
                rows_per_image: Some(SKY_VIEW_HEIGHT),
            },
            wgpu::Extent3d { width: SKY_VIEW_WIDTH, height: SKY_VIEW_HEIGHT, depth_or_array_layers: 1 },
        );
        let summary = SkySummary::from(&light);
        self.sky = Some((sun, exposure, summary));
        summary
    }

    /// GPU memory of the shadow map and the sky-view table, in bytes.
    pub fn gpu_bytes(&self) -> u64 {
        u64::from(SHADOW_MAP_SIZE) * u64::from(SHADOW_MAP_SIZE) * 4
            + u64::from(SKY_VIEW_WIDTH * SKY_VIEW_HEIGHT) * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sun_matrix_frames_the_terrain() {
        let (min, max) = (Vec3::new(-10.0, -1.5, -10.0), Vec3::new(10.0, 2.3, 10.0));
        for sun in [Vec3::new(-0.7, 0.4, -0.5), Vec3::Y, Vec3::new(1.0, 0.0, 0.0)] {
            let matrix = sun_matrix(sun.normalize(), min, max);
            for i in 0..8 {
                let corner = Vec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                );
                let clip = matrix.project_point3(corner);
                assert!(clip.x.abs() <= 1.0001 && clip.y.abs() <= 1.0001, "{sun}: {clip}");
                assert!((0.0..=1.0).contains(&clip.z), "{sun}: {clip}");
            }
            // Nearer the sun is nearer the shadow map's camera.
            let high = matrix.project_point3(Vec3::new(0.0, 2.0, 0.0) + sun.normalize() * 0.5);
            let low = matrix.project_point3(Vec3::new(0.0, 2.0, 0.0));
            assert!(high.z < low.z);
        }
    }

    #[test]
    fn waves_drift_at_the_course_speed() {
        let config = SceneConfig::default();
        let settings = Settings::default();
        let inputs = |t| SceneInputs {
            time_seconds: t,
            frame_size: (4, 4),
            shadow_matrix: Mat4::IDENTITY,
            sky: SkySummary::from(&Atmosphere::earth().sky(Vec3::Y, 1.0)),
        };
        // 0.2 units a second over tiles of 2 units: 0.1 tile a second, drifting toward -x, -z.
        let later = SceneUniforms::new(&settings, &config, &inputs(1.0));
        assert!(
            (later.waves[0] - 0.9).abs() < 1e-5 && (later.waves[1] - 0.9).abs() < 1e-5,
            "{:?}",
            later.waves
        );
        // Wrapped, so a long-running window keeps its precision (the course's speed is an f32:
        // over a week it drifts from 0.1 tile a second by about a thousandth of a tile).
        let week = SceneUniforms::new(&settings, &config, &inputs(7.0 * 86400.0 + 1.0));
        assert!((0.0..1.0).contains(&week.waves[0]));
        assert!((week.waves[0] - later.waves[0]).abs() < 1e-2, "{:?}", week.waves);
    }
}
