//! The shadow map: the terrain's depth seen from the sun (an orthographic view along its light),
//! drawn once per sun direction. The land is static, so moving the camera never redraws it.

use super::grid::{GridPass, GridTerrain};
use super::pipeline::{PassContext, PipelineSpec, pipeline, shader_source};

/// The shadow map's program (the grid seen from the sun, depth only): the WGSL source its pipeline is built from.
pub(super) const SHADER: &str = shader_source!("heights.wgsl", "grid.wgsl");

/// The depth-only pipeline that draws the grid from the sun.
#[derive(Debug)]
pub struct ShadowPass {
    pipeline: wgpu::RenderPipeline,
}

impl ShadowPass {
    /// The pipeline, for the grid's bind group `layout` (group 1).
    pub fn new(context: &PassContext<'_>, layout: &wgpu::BindGroupLayout) -> Self {
        let buffers = GridTerrain::buffer_layouts();
        let layouts = [layout];
        let spec = PipelineSpec {
            fragment_entry: None,
            // Slope-scaled bias against shadow acne on slopes lit at a grazing angle.
            depth_bias: wgpu::DepthBiasState { constant: 2, slope_scale: 2.0, clamp: 0.0 },
            ..PipelineSpec::new("shadow", SHADER, &layouts, &buffers)
        };
        Self { pipeline: pipeline(context, &spec, false) }
    }

    /// Draws the patches the grid chose for [`GridPass::Sun`] into `target` (the shadow map),
    /// with the sun's `frame` uniforms and the grid's `group`.
    pub fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        grid: &GridTerrain,
        frame: &wgpu::BindGroup,
        group: &wgpu::BindGroup,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow map"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: target,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, frame, &[]);
        pass.set_bind_group(1, group, &[]);
        grid.draw(&mut pass, GridPass::Sun);
    }
}
