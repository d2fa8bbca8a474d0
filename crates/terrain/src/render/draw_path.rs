//! How the course look's static mesh issues its draws, by what the GPU can do. The mesh's chunks
//! index their vertices from a base vertex each; WebGL2 (and OpenGL ES 3.0/3.1) has no base
//! vertex, so there each chunk's draw binds the vertex buffer at the chunk's first vertex
//! instead. Every path draws the same triangles in the same order: the pictures are identical.

/// A way of drawing the static mesh's chunks, asked for with
/// [`super::Renderer::set_land_draw_path`]. The renderer never takes a path the GPU lacks: it
/// falls back to the next one down ([`LandDrawPath::Indirect`] to
/// [`LandDrawPath::BaseVertex`] to [`LandDrawPath::VertexOffset`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LandDrawPath {
    /// One multi-draw-indirect call per pass (the default, where the GPU draws indirectly).
    #[default]
    Indirect,
    /// One indexed draw per chunk, passing the chunk's base vertex.
    BaseVertex,
    /// One indexed draw per chunk with base vertex 0, the vertex buffer bound at an offset of the
    /// chunk's base vertex times the vertex stride (12 bytes): what WebGL2 can do.
    VertexOffset,
}

/// What the GPU offers the land's draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct DrawSupport {
    /// Indirect draws (`DownlevelFlags::INDIRECT_EXECUTION`); these always honour a base vertex.
    pub indirect: bool,
    /// A non-zero base vertex in direct indexed draws (`DownlevelFlags::BASE_VERTEX`).
    pub base_vertex: bool,
}

impl DrawSupport {
    /// What `adapter` offers.
    pub fn of(adapter: &wgpu::Adapter) -> Self {
        let flags = adapter.get_downlevel_capabilities().flags;
        Self {
            indirect: flags.contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION),
            base_vertex: flags.contains(wgpu::DownlevelFlags::BASE_VERTEX),
        }
    }

    /// The path taken when `wanted` is asked for: it, or the first one down that the GPU has.
    pub fn resolve(self, wanted: LandDrawPath) -> LandDrawPath {
        match wanted {
            LandDrawPath::Indirect if self.indirect => LandDrawPath::Indirect,
            LandDrawPath::Indirect | LandDrawPath::BaseVertex if self.base_vertex => LandDrawPath::BaseVertex,
            _ => LandDrawPath::VertexOffset,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_the_gpu_lacks_falls_back_to_one_it_has() {
        let all = [LandDrawPath::Indirect, LandDrawPath::BaseVertex, LandDrawPath::VertexOffset];
        let full = DrawSupport { indirect: true, base_vertex: true };
        for path in all {
            assert_eq!(full.resolve(path), path, "a GPU with everything takes the path asked for");
        }
        // No indirect draws (WebGL2, GLES 3.0): per chunk, with a base vertex where there is one.
        let direct = DrawSupport { indirect: false, base_vertex: true };
        assert_eq!(direct.resolve(LandDrawPath::Indirect), LandDrawPath::BaseVertex);
        assert_eq!(direct.resolve(LandDrawPath::VertexOffset), LandDrawPath::VertexOffset);
        // WebGL2: neither, so never a base vertex.
        let webgl = DrawSupport { indirect: false, base_vertex: false };
        for path in all {
            assert_eq!(webgl.resolve(path), LandDrawPath::VertexOffset);
        }
        // Indirect without direct base vertex: indirect draws honour it anyway.
        let indirect_only = DrawSupport { indirect: true, base_vertex: false };
        assert_eq!(indirect_only.resolve(LandDrawPath::Indirect), LandDrawPath::Indirect);
        assert_eq!(indirect_only.resolve(LandDrawPath::BaseVertex), LandDrawPath::VertexOffset);
    }
}
