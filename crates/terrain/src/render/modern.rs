//! The modern look: the land lit by the sun (with its shadows) and the sky, faded into the
//! sky's colour by the fog; the sky graded for the sun; the water reflecting a texture of the
//! mirrored world and showing the sea floor. A frame is up to three passes: the shadow map (only
//! when the sun has moved), the reflection (at a fraction of the frame's size), and the frame.

use glam::Vec3;

use super::grid::{GridPass, GridTerrain, upload_view};
use super::light_map::LightMap;
use super::lighting::{Lighting, SceneInputs, SceneUniforms, sun_matrix};
use super::pipeline::{Binding, PassContext, PipelineSpec, bind_group, pipeline, shader_source};
use super::reflection::{REFLECTION_FORMAT, ReflectionTarget};
use super::sea::SeaPass;
use super::shadow::ShadowPass;
use super::sky::{SkyFaces, SkyPass};
use super::texture::nearest_level_sampler;
use super::{DrawBudget, RenderError, Renderer};
use crate::config::SceneConfig;
use crate::settings::Settings;
use crate::world::World;

/// The modern look's draws, in the order a frame makes them (the first two into the reflection;
/// they count even when the water reflects nothing).
pub(super) const DRAWS: [&str; 5] = ["reflected land", "reflected sky", "land", "sky", "water"];

/// The modern look's land (the grid, lit): the WGSL source its pipeline is built from.
pub(super) const LAND_SHADER: &str =
    shader_source!("lighting.wgsl", "heights.wgsl", "grid.wgsl", "grid_modern.wgsl");

/// The modern look's GPU resources (the grid is the renderer's).
#[derive(Debug)]
pub struct ModernLook {
    sky: SkyPass,
    lighting: Lighting,
    land_layout: wgpu::BindGroupLayout,
    land_group: wgpu::BindGroup,
    /// The ground's materials (group 3 of the land): the land's shape and the material noise.
    ground_layout: wgpu::BindGroupLayout,
    ground_group: wgpu::BindGroup,
    /// The land as it is and its reflection (filled), then their wireframe versions.
    land: [wgpu::RenderPipeline; 2],
    wireframe: Option<[wgpu::RenderPipeline; 2]>,
    show_wireframe: bool,
    /// Whether the land's pipelines draw the ground's materials (`GROUND_MATERIALS`).
    materials: bool,
    shadow: ShadowPass,
    /// The grid's heights alone (the shadow pass's group 1).
    heights_group: wgpu::BindGroup,
    light_map: LightMap,
    sea: SeaPass,
    albedo: wgpu::TextureView,
    reflection: Option<ReflectionTarget>,
    /// The box around the terrain, for the sun's view.
    bounds: (Vec3, Vec3),
    gpu_bytes: u64,
}

impl ModernLook {
    /// Uploads what the modern look needs of `world` (its albedo and clear sky where it has
    /// them), drawing over `grid`, with the ground's materials (`materials`) or without.
    pub fn new(
        context: &PassContext<'_>,
        world: &World,
        config: &SceneConfig,
        grid: &GridTerrain,
        materials: bool,
    ) -> Result<Self, RenderError> {
        let device = context.device;
        let faces = SkyFaces::new(context, world.clear_sky())?;
        let lighting = Lighting::new(device);
        let reflection_context = PassContext { target_format: REFLECTION_FORMAT, ..*context };
        let sky = SkyPass::modern(
            context,
            &reflection_context,
            &faces,
            config,
            (&lighting.layout, &lighting.group),
        );
        let albedo = upload_view(context, "albedo map", world.albedo_map())?;
        let detail = upload_view(context, "detail map", &world.detail_map)?;
        let light_map = LightMap::new(context, grid, &lighting.layout);
        let (land_layout, land_group) =
            grid.land_group(device, "land (modern)", &albedo, &detail, light_map.view());
        let ground_map = crate::world::ground::ground_map(&world.heightmap, config, world.erosion.as_ref());
        let noise = crate::world::ground::material_noise();
        let ground_bytes = (ground_map.as_raw().len() + noise.as_raw().len()) as u64 * 4 / 3;
        let ground_view = upload_view(context, "ground map", &ground_map)?;
        let noise_view = upload_view(context, "material noise", &noise)?;
        let (ground_layout, ground_group) = bind_group(
            device,
            "ground",
            &[
                Binding::Texture(&ground_view),
                Binding::Texture(&noise_view),
                Binding::Sampler(&nearest_level_sampler(device)),
            ],
        );
        let land = land_pipelines(
            context,
            [&land_layout, &lighting.layout, &ground_layout],
            wgpu::PolygonMode::Fill,
            materials,
        );
        let (heights_layout, heights_group) = grid.heights_group(device);
        let shadow = ShadowPass::new(context, &heights_layout);
        let sea = SeaPass::new(
            context,
            config,
            grid,
            (&albedo, light_map.view()),
            (&lighting.layout, &lighting.group),
        )?;
        let half = config.terrain_length / 2.0;
        let bounds = (
            Vec3::new(-half, config.height_of_level(0.0).min(0.0), -half),
            Vec3::new(half, config.height_of_level(255.0), half),
        );
        let images = world.albedo_map().as_raw().len() + world.detail_map.as_raw().len();
        let gpu_bytes =
            faces.bytes + images as u64 * 4 / 3 + lighting.gpu_bytes() + sea.gpu_bytes() + ground_bytes;
        Ok(Self {
            sky,
            lighting,
            land_layout,
            land_group,
            ground_layout,
            ground_group,
            land,
            wireframe: None,
            show_wireframe: false,
            materials,
            shadow,
            heights_group,
            light_map,
            sea,
            albedo,
            reflection: None,
            bounds,
            gpu_bytes,
        })
    }

    /// GPU memory of the look's own resources (not the shared grid), in bytes: the light map,
    /// then the rest.
    pub fn gpu_bytes(&self) -> (u64, u64) {
        let rest = self.gpu_bytes + self.reflection.as_ref().map_or(0, ReflectionTarget::gpu_bytes);
        (self.light_map.gpu_bytes(), rest)
    }

    /// Draws the land's edges (`wireframe`) or its faces, where the GPU can, with the ground's
    /// materials (`materials`) or without: the land's pipelines are built again when that changes.
    pub fn set_land(&mut self, context: &PassContext<'_>, wireframe: bool, materials: bool) {
        let layouts = [&self.land_layout, &self.lighting.layout, &self.ground_layout];
        if materials != self.materials {
            self.land = land_pipelines(context, layouts, wgpu::PolygonMode::Fill, materials);
            self.wireframe = None;
            self.materials = materials;
        }
        let able = context.device.features().contains(wgpu::Features::POLYGON_MODE_LINE);
        if wireframe && able && self.wireframe.is_none() {
            self.wireframe = Some(land_pipelines(context, layouts, wgpu::PolygonMode::Line, materials));
        }
        self.show_wireframe = wireframe && able;
    }
}

/// The modern land's pipelines: as it is (into the frame) and reflected (into the reflection).
/// `layouts`: the land's group (1), the lighting (2) and the ground's materials (3);
/// `materials`: whether they draw the ground's materials.
fn land_pipelines(
    context: &PassContext<'_>,
    layouts: [&wgpu::BindGroupLayout; 3],
    polygon_mode: wgpu::PolygonMode,
    materials: bool,
) -> [wgpu::RenderPipeline; 2] {
    let buffers = GridTerrain::buffer_layouts();
    let constants = [("GROUND_MATERIALS", if materials { 1.0 } else { 0.0 })];
    let spec = PipelineSpec {
        polygon_mode,
        vertex_entry: "vs_lit",
        constants: &constants,
        ..PipelineSpec::new("land (modern)", LAND_SHADER, &layouts, &buffers)
    };
    let reflected = PipelineSpec { fragment_entry: Some("fs_reflected"), ..spec };
    let reflection_context = PassContext { target_format: REFLECTION_FORMAT, ..*context };
    [pipeline(context, &spec, false), pipeline(&reflection_context, &reflected, true)]
}

impl Renderer {
    /// Brings the modern look's per-frame state up to date: the scene uniforms, the reflection's
    /// size, the patches of the reflection and of the sun's view. Returns whether the shadow map
    /// must be drawn.
    pub(super) fn prepare_modern(&mut self, gpu: &super::Gpu, size: (u32, u32), time_seconds: f64) -> bool {
        let settings: &Settings = &self.settings;
        let (Some(modern), Some(grid)) = (&mut self.modern, &mut self.grid) else { return false };
        let sky = modern.lighting.update_sky(&gpu.queue, settings.sun_direction(), settings.sun.intensity);
        if !self.config.sea {
            // Below the horizon, where no land is drawn, the frame shows the horizon's colour
            // (as `frame::clear_colour` does for a painted sky).
            let linear = |c: f32| super::frame::srgb_to_linear(f64::from(c));
            self.clear = wgpu::Color {
                r: linear(sky.horizon.x),
                g: linear(sky.horizon.y),
                b: linear(sky.horizon.z),
                a: 1.0,
            };
        }
        // The light that casts shadows: the sun, or the moon at night.
        let sun = sky.key_direction;
        let shadow_matrix = sun_matrix(sun, modern.bounds.0, modern.bounds.1);
        let inputs = SceneInputs { time_seconds, frame_size: size, shadow_matrix, sky };
        let uniforms = SceneUniforms::new(settings, &self.config, &inputs);
        gpu.queue.write_buffer(&modern.lighting.buffer, 0, bytemuck::bytes_of(&uniforms));
        // The reflection, at the settings' fraction of the frame.
        let scale = settings.water.reflection.scale();
        let wanted = (scale > 0.0).then(|| ReflectionTarget::size_for(size, scale));
        if modern.reflection.as_ref().map(ReflectionTarget::size) != wanted {
            modern.reflection = wanted.map(|size| ReflectionTarget::new(&gpu.device, size));
            let view = modern.reflection.as_ref().map(ReflectionTarget::view);
            modern.sea.bind(&gpu.device, grid, (&modern.albedo, modern.light_map.view()), view);
        }
        // The shadow map and the light map, drawn again only when the sun has moved or shadows
        // were switched.
        let shadows = settings.sun.shadows;
        let redraw = modern.light_map.stale(sun, shadows);
        if redraw {
            modern.light_map.prepare(&gpu.queue, sun, shadows);
        }
        if redraw && shadows {
            let uniforms =
                super::uniforms::FrameUniforms::new(shadow_matrix, false, glam::Vec2::ZERO, sun * 1000.0);
            gpu.queue.write_buffer(&self.frame_buffers[2], 0, bytemuck::bytes_of(&uniforms));
            let texels_per_unit =
                super::lighting::SHADOW_MAP_SIZE as f32 / (modern.bounds.1 - modern.bounds.0).length();
            let view = crate::world::quadtree::TreeView {
                eye: sun * 1000.0,
                frustum: crate::camera::Frustum::from_view_projection(shadow_matrix),
                pixels_per_unit: texels_per_unit,
                max_error_pixels: 1.0,
                mirrored: false,
                orthographic: true,
            };
            grid.prepare(&gpu.device, &gpu.queue, GridPass::Sun, &view);
        }
        redraw
    }

    /// Draws the modern look: the shadow map and the light map when `relight` asks, the
    /// reflection, then the frame (land nearest first, sky, water).
    pub(super) fn draw_modern(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        relight: bool,
    ) {
        let (Some(modern), Some(grid), Some(depth)) = (&self.modern, &self.grid, &self.depth) else { return };
        let [direct, mirrored, sun] = &self.frame_groups;
        if relight {
            if self.settings.sun.shadows {
                modern.shadow.draw(encoder, &modern.lighting.shadow_view, grid, sun, &modern.heights_group);
            }
            modern.light_map.draw(encoder, direct, &modern.lighting.group);
        }
        let land = match (&modern.wireframe, modern.show_wireframe) {
            (Some(wireframe), true) => wireframe,
            _ => &modern.land,
        };
        let mut budget = DrawBudget(self.draw_limit);
        // Counted whether or not the water reflects, so that the draws keep their places.
        let (reflected_land, reflected_sky) = (budget.take(), budget.take());
        // Without a sea nothing shows the reflection.
        let reflection = modern.reflection.as_ref().filter(|_| self.config.sea);
        if let Some(reflection) = reflection {
            let mut pass = reflection.begin(encoder);
            if reflected_land {
                pass.set_pipeline(&land[1]);
                pass.set_bind_group(0, mirrored, &[]);
                pass.set_bind_group(1, &modern.land_group, &[]);
                pass.set_bind_group(2, &modern.lighting.group, &[]);
                pass.set_bind_group(3, &modern.ground_group, &[]);
                grid.draw(&mut pass, GridPass::Mirrored);
            }
            if reflected_sky {
                modern.sky.draw(&mut pass, mirrored, true);
            }
        }
        let mut pass = super::frame::begin_pass(encoder, "scene", target, depth.view(), self.clear);
        if budget.take() {
            pass.set_pipeline(&land[0]);
            pass.set_bind_group(0, direct, &[]);
            pass.set_bind_group(1, &modern.land_group, &[]);
            pass.set_bind_group(2, &modern.lighting.group, &[]);
            pass.set_bind_group(3, &modern.ground_group, &[]);
            grid.draw(&mut pass, GridPass::Direct);
        }
        if budget.take() {
            modern.sky.draw(&mut pass, direct, false);
        }
        if budget.take() && self.config.sea {
            modern.sea.draw(&mut pass, direct);
        }
    }
}
