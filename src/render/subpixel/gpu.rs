//! The GPU half of the antialiased lookup ([`ShadowLookup::SubPixelAa`]):
//! compute passes after the camera pass that turn each pixel's single
//! shadow bit into a 32-bit occlusion word (`shaders/aa_passes.wgsl`).
//!
//! Why a post-pass rather than a lookup file: the lookup seam returns one
//! bit per light and the masks have no room for a fraction, and the paper's
//! expensive path needs whole-scene data (silhouette edges, triangle lists)
//! that a fragment shader cannot build. So the mode renders exactly like
//! the depth compare (its shadow bit, colour and masks are the standard
//! lookup's) and adds, per light: the silhouette mask and its summed-area
//! table, triangle lists of the tiles near silhouettes, and the per-pixel
//! facet visibility: occlusion words and, as in the paper, validity words
//! (samples whose facet point a listed triangle hides from the camera do not
//! count). [`Renderer::read_occlusion`] and [`Renderer::read_validity`] read
//! them back; [`Renderer::read_aa_stats`] the per-light counts.
//!
//! **Overflow policy**: the triangle–tile lists hold at most
//! [`PAIR_CAPACITY`] entries per light; a pixel whose footprint touches a
//! list tile whose list did not fit keeps the standard bit in every sample and
//! is counted in [`AaStats::overflow_pixels`]. A footprint touching more
//! than 36 tiles, or a tile without silhouette texels nearby (footprints
//! wider than a tile), does the same, counted in [`AaStats::wide_pixels`].
//!
//! [`ShadowLookup::SubPixelAa`]: super::super::ShadowLookup::SubPixelAa

use std::borrow::Cow;

use wgpu::util::DeviceExt;

use super::bitmask::HalfPlaneTable;
use super::reference::EdgeAdjacency;
use super::{AaSamples, SAMPLE_POSITIONS};
use crate::mesh::Mesh;
use crate::render::passes::storage_entry;
use crate::render::{device, RenderError, Renderer};
use crate::LightMatrix;

/// Entries of one light's triangle–tile lists (16 MiB of `u32`).
pub const PAIR_CAPACITY: u32 = 1 << 22;
/// Tile side in map texels (`TILE` in the shader): a tile's activity and
/// the footprint width limit.
const TILE: u32 = 8;
/// Side of the list tiles in map texels (`LIST_TILE` in the shader): the
/// triangle lists are kept per list tile, (TILE / LIST_TILE)² per tile.
/// With 4 the exact path reads about half the entries of 8 (one list per
/// tile). Session 10's missed list row with 4 was llvmpipe's loop limit
/// (65 535 iterations per invocation), which the old one-iteration-per-entry
/// scan reached on wide footprints with either size; the scans now cull a
/// block of entries per iteration (issue-18 note, session 12).
const LIST_TILE: u32 = 4;
// `enter_lists` in the shader writes a tile's list tiles out, at most 2x2.
const _: () = assert!(TILE.is_multiple_of(LIST_TILE) && TILE / LIST_TILE <= 2);
/// Statistics words per light (`STATS_PER_LIGHT`) and their block.
const STATS_PER_LIGHT: usize = 16;
const STATS_WORDS: u64 = 512;
// Every light of a frame has its statistics words.
const _: () = assert!(STATS_PER_LIGHT * crate::MAX_LIGHTS <= STATS_WORDS as usize);

/// The statistics' layout as WGSL constants, prepended to the passes and to
/// `ARGS_SHADER` (one source of truth for both languages).
fn stats_constants() -> String {
    format!("const STATS_PER_LIGHT: u32 = {STATS_PER_LIGHT}u;\nconst STATS_WORDS: u32 = {STATS_WORDS}u;\n")
}

/// Dynamic-offset stride of the per-light parameters.
const PARAM_STRIDE: u64 = 256;
/// Workgroup size of the flat passes.
const GROUP: u32 = 64;
/// Bytes of one light's indirect dispatch arguments for `visibility_exact`.
const ARGS_STRIDE: u64 = 16;

/// Turns light `params.light`'s exact-path queue length (statistics word
/// `STAT_QUEUE`, 5, of `tile_words`) into `visibility_exact`'s indirect
/// dispatch arguments: one invocation per queued pixel in workgroups of 64,
/// 2D beyond the per-dimension limit (`flat_id`). A module of its own: the
/// arguments buffer must not be bound to the dispatch that reads it as
/// arguments, and every binding of the passes' group 1 is.
const ARGS_SHADER: &str = "
struct Light { light: u32 }
@group(0) @binding(0) var<uniform> params: Light;
@group(0) @binding(1) var<storage, read> stats: array<u32>;
@group(0) @binding(2) var<storage, read_write> args: array<u32>;

@compute @workgroup_size(1)
fn exact_args() {
    // Word STAT_QUEUE (5) of the light's STATS_PER_LIGHT statistics
    // (prepended, as for the passes).
    let groups = (stats[params.light * STATS_PER_LIGHT + 5u] + 63u) / 64u;
    let a = params.light * 4u;
    args[a] = min(groups, 65535u);
    args[a + 1u] = (groups + 65534u) / 65535u;
    args[a + 2u] = 1u;
}
";

/// What the antialiased passes did for one light of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct AaStats {
    /// Triangle–tile list entries wanted (may exceed [`PAIR_CAPACITY`]).
    pub pairs: u32,
    /// Pixels that took the exact path (silhouette texel in the footprint).
    pub exact_pixels: u32,
    /// Pixels that kept the standard bit because a list overflowed.
    pub overflow_pixels: u32,
    /// Pixels that kept the standard bit because the footprint was too wide,
    /// or because the exact scan ended before its last list tile without
    /// every sample occluded (cut short by the backend: llvmpipe and
    /// lavapipe end a shader invocation's loops after 65 535 iterations).
    pub wide_pixels: u32,
    /// Triangle–facet tests of the exact path, all pixels together (list
    /// entries whose box meets the pixel's footprint; every entry of its
    /// tiles with culling off). A pixel's walk stops once every sample is
    /// occluded, so this count depends on the lists' (atomic) order and may
    /// differ from run to run; the words do not.
    pub triangle_tests: u32,
    /// Of [`exact_pixels`](Self::exact_pixels), those without a silhouette
    /// texel in the footprint that took the exact path because their depth
    /// compare is uncertain (the map's depth within the bias band of the
    /// receiver's, or a degenerate footprint).
    pub uncertain_pixels: u32,
    /// List entries the exact path read, all pixels it served together (the
    /// entries of the footprints' list tiles, culled or tested, up to a pixel's
    /// early stop; so run-dependent as
    /// [`triangle_tests`](Self::triangle_tests)): the length of the exact
    /// path's scan, a large part of its cost on lavapipe.
    pub entries_scanned: u32,
    /// Texels the silhouette mask marked: texels a silhouette edge crosses
    /// that the depth check kept (it drops a texel where the edge lies
    /// behind the light's depth map in the texel's whole 3x3 neighbourhood).
    pub silhouette_texels: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsRaw {
    light: u32,
    tiles_x: u32,
    tiles_y: u32,
    capacity: u32,
    width: u32,
    height: u32,
    edge_count: u32,
    triangle_count: u32,
    bias: f32,
    sample_mask: u32,
    map_w: u32,
    map_h: u32,
    sat_base: u32,
    tile_stride: u32,
    box_base: u32,
    queue_base: u32,
    cull: u32,
    valid_base: u32,
    validity: u32,
    uncertain: u32,
    depth_bias: f32,
    slope_scale: f32,
    bias_clamp: f32,
    screen_base: u32,
    gate: u32,
    depth_check: u32,
    _pad: [u32; 2],
}

/// One mesh edge for the silhouette pass (`Edge` in the shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct EdgeRaw {
    a: [f32; 4],
    b: [f32; 4],
    f0: [f32; 4],
    f1: [f32; 4],
}

/// The edges of `mesh` as the silhouette pass reads them: two-triangle
/// edges with both planes; boundary and non-manifold edges flagged as
/// silhouettes for every light (conservative: more texels take the exact
/// path, none is missed).
pub(crate) fn edge_records(mesh: &Mesh) -> Vec<EdgeRaw> {
    let plane = |t: u32| {
        let k = 3 * t as usize;
        let [a, b, c] = [0, 1, 2].map(|i| mesh.positions[mesh.indices[k + i] as usize]);
        let n = (b - a).cross(c - a);
        [n.x, n.y, n.z, -n.dot(a)]
    };
    EdgeAdjacency::new(mesh)
        .edges()
        .map(|([a, b], tris)| {
            let always = tris.len() != 2;
            EdgeRaw {
                a: [a.x, a.y, a.z, if always { 1.0 } else { 0.0 }],
                b: [b.x, b.y, b.z, 0.0],
                f0: if always { [0.0; 4] } else { plane(tris[0]) },
                f1: if always { [0.0; 4] } else { plane(tris[1]) },
            }
        })
        .collect()
}

/// Buffers sized for the largest frame so far.
struct Sized {
    map_texels: u64,
    tiles: u64,
    pixels: u64,
    lights: u64,
    triangles: u64,
    map_words: wgpu::Buffer,
    tile_words: wgpu::Buffer,
    tile_list: wgpu::Buffer,
    occlusion: wgpu::Buffer,
}

/// What the last antialiased frame left in the buffers.
#[derive(Clone, Copy, Debug)]
struct LastFrame {
    width: u32,
    height: u32,
    lights: usize,
    /// The list capacity the frame ran with.
    capacity: u32,
}

/// Pipelines, the scene's edges and the buffers of the antialiased passes.
pub(crate) struct AaPass {
    group0: wgpu::BindGroupLayout,
    group1: wgpu::BindGroupLayout,
    /// silhouette, sat_rows, sat_cols, tile_count_pass, tile_scan, tile_write, visibility,
    /// visibility_exact, classify, settle.
    pipelines: Vec<wgpu::ComputePipeline>,
    /// `exact_args` (`ARGS_SHADER`), its bind group layout and the
    /// arguments buffer (ARGS_STRIDE bytes per light).
    args_pipeline: wgpu::ComputePipeline,
    args_group: wgpu::BindGroupLayout,
    args: wgpu::Buffer,
    edges: wgpu::Buffer,
    edge_count: u32,
    table: wgpu::Buffer,
    params: wgpu::Buffer,
    sized: Option<Sized>,
    bias: f32,
    last: Option<LastFrame>,
    /// List entries per light actually used (at most [`PAIR_CAPACITY`]).
    capacity: u32,
    /// Per-pixel culling of list entries by the triangles' boxes (on unless
    /// a test turns it off to compare).
    cull: bool,
    /// The validity mask (on unless a test turns it off to compare).
    validity: bool,
    /// The exact path for pixels whose depth compare is uncertain (on
    /// unless a test turns it off to compare).
    uncertain: bool,
    /// The screen-box gate of the hidden test (on unless a test turns it
    /// off to compare).
    gate: bool,
    /// The silhouette pass's depth check (on unless a test turns it off to
    /// compare).
    depth_check: bool,
}

const ENTRY_POINTS: [&str; 10] = [
    "silhouette",
    "sat_rows",
    "sat_cols",
    "tile_count_pass",
    "tile_scan",
    "tile_write",
    "visibility",
    "visibility_exact",
    "classify",
    "settle",
];

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    storage_entry(binding, wgpu::ShaderStages::COMPUTE, read_only, false)
}

fn uniform(binding: u32, dynamic: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

impl AaPass {
    /// Builds the pipelines and uploads `mesh`'s edges and the half-plane
    /// table. `bias`: world units a blocker's plane is pushed away from the
    /// light (the receiver's own triangle must not shadow its facet).
    pub(crate) fn new(device: &wgpu::Device, mesh: &Mesh, bias: f32) -> Self {
        let group0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel aa group 0"),
            entries: &[uniform(0, false), uniform(1, false)],
        });
        let group1 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel aa group 1"),
            entries: &[
                uniform(0, true),
                storage(1, true),
                storage(2, false),
                storage(3, false),
                storage(4, false),
                storage(5, true),
                storage(6, true),
                uniform(7, false),
                storage(8, false),
                wgpu::BindGroupLayoutEntry {
                    binding: 9,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 10,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel aa pipeline layout"),
            bind_group_layouts: &[Some(&group0), Some(&group1)],
            immediate_size: 0,
        });
        // common.wgsl's `shade` calls a lookup's `in_shadow`: a stub here.
        // The sub-sample positions as the CPU side has them (exact in f32:
        // cell centres of an 8x8 grid).
        let positions: Vec<String> =
            SAMPLE_POSITIONS.iter().map(|p| format!("vec2<f32>({:?}, {:?})", p.x as f32, p.y as f32)).collect();
        let source = format!(
            "{}{}fn in_shadow(light: Light, world: vec3<f32>) -> bool {{ return false; }}\n\
             const LIST_TILE: u32 = {LIST_TILE}u;\nconst PER_TILE: i32 = {};\n{}\
             const SAMPLE_POSITIONS = array<vec2<f32>, 32>({});\n{}",
            include_str!("../../../shaders/light_depth.wgsl"),
            include_str!("../../../shaders/common.wgsl"),
            TILE / LIST_TILE,
            stats_constants(),
            positions.join(", "),
            include_str!("../../../shaders/aa_passes.wgsl"),
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lixel aa passes"),
            source: wgpu::ShaderSource::Wgsl(Cow::Owned(source)),
        });
        let pipelines = ENTRY_POINTS
            .iter()
            .map(|entry| {
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(&format!("lixel aa {entry}")),
                    layout: Some(&layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
            })
            .collect();
        let args_group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel aa exact_args group"),
            entries: &[uniform(0, true), storage(1, true), storage(2, false)],
        });
        let args_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("lixel aa exact_args"),
            layout: Some(&device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("lixel aa exact_args layout"),
                bind_group_layouts: &[Some(&args_group)],
                immediate_size: 0,
            })),
            module: &device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("lixel aa exact_args"),
                source: wgpu::ShaderSource::Wgsl(Cow::Owned(format!("{}{ARGS_SHADER}", stats_constants()))),
            }),
            entry_point: Some("exact_args"),
            compilation_options: Default::default(),
            cache: None,
        });
        let args = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel aa visibility_exact dispatch arguments"),
            size: ARGS_STRIDE * crate::render::MAX_LIGHTS as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        let records = edge_records(mesh);
        // A zero-sized storage binding is invalid: keep one (unused) record.
        let padded = if records.is_empty() { vec![bytemuck::Zeroable::zeroed()] } else { records.clone() };
        let edges = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lixel aa edges"),
            contents: bytemuck::cast_slice(&padded),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let table = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lixel aa half-plane table"),
            contents: bytemuck::cast_slice(HalfPlaneTable::new().words()),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel aa parameters"),
            size: PARAM_STRIDE * crate::render::MAX_LIGHTS as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            group0,
            group1,
            pipelines,
            args_pipeline,
            args_group,
            args,
            edges,
            edge_count: records.len() as u32,
            table,
            params,
            sized: None,
            bias,
            last: None,
            capacity: PAIR_CAPACITY,
            cull: true,
            validity: true,
            uncertain: true,
            gate: true,
            depth_check: true,
        }
    }

    fn buffer(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
        wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }
    }

    /// Binding 0 of the pass groups: one light's parameters.
    fn params_entry(&self) -> wgpu::BindGroupEntry<'_> {
        wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &self.params,
                offset: 0,
                size: wgpu::BufferSize::new(std::mem::size_of::<ParamsRaw>() as u64),
            }),
        }
    }

    fn ensure(&mut self, device: &wgpu::Device, map_texels: u64, tiles: u64, pixels: u64, lights: u64, triangles: u64) {
        if self.sized.as_ref().is_some_and(|s| {
            s.map_texels >= map_texels
                && s.tiles >= tiles
                && s.pixels >= pixels
                && s.lights >= lights
                && s.triangles >= triangles
        }) {
            return;
        }
        let old = self.sized.as_ref();
        let map_texels = map_texels.max(old.map_or(0, |s| s.map_texels));
        let tiles = tiles.max(old.map_or(0, |s| s.tiles));
        let pixels = pixels.max(old.map_or(0, |s| s.pixels));
        let lights = lights.max(old.map_or(0, |s| s.lights));
        let triangles = triangles.max(old.map_or(0, |s| s.triangles));
        let buffer = |label: &str, words: u64, copy_src: bool| {
            let mut usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
            if copy_src {
                usage |= wgpu::BufferUsages::COPY_SRC;
            }
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 4 * words.max(1),
                usage,
                mapped_at_creation: false,
            })
        };
        self.sized = Some(Sized {
            map_texels,
            tiles,
            pixels,
            lights,
            triangles,
            map_words: buffer("lixel aa mask and summed-area table", 2 * map_texels, true),
            // The statistics, then per list tile its count, cursor, offset
            // and per tile whether an uncertain pixel forced it active.
            tile_words: buffer("lixel aa statistics and tiles", STATS_WORDS + 4 * tiles, true),
            // The lists, each triangle's box in the map (4 f32), its box on
            // the screen (4 f32), then the queue of the exact path's pixels.
            tile_list: buffer(
                "lixel aa triangle-tile lists, boxes and pixel queue",
                u64::from(PAIR_CAPACITY) + 8 * triangles + pixels,
                true,
            ),
            // Every light's occlusion words, then every light's validity words.
            occlusion: buffer("lixel aa occlusion and validity words", 2 * pixels * lights, true),
        });
    }

    /// Encodes the passes for every light of the frame (after the camera
    /// pass wrote its masks into `masks`).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: (&wgpu::Buffer, &wgpu::Buffer),
        scene: (&wgpu::Buffer, &wgpu::Buffer, u32),
        (masks, maps): (&wgpu::TextureView, &wgpu::TextureView),
        bias: &crate::render::ShadowBias,
        (width, height): (u32, u32),
        lights: &[LightMatrix],
        samples: AaSamples,
    ) {
        let map_texels = lights.iter().map(|m| u64::from(m.map_size.width) * u64::from(m.map_size.height)).max();
        let tiles = lights
            .iter()
            .map(|m| u64::from(m.map_size.width.div_ceil(LIST_TILE)) * u64::from(m.map_size.height.div_ceil(LIST_TILE)))
            .max();
        let pixels = u64::from(width) * u64::from(height);
        let (vertices, indices, triangles) = scene;
        self.ensure(
            device,
            map_texels.unwrap_or(1),
            tiles.unwrap_or(1),
            pixels,
            lights.len().max(1) as u64,
            u64::from(triangles),
        );
        let sized = self.sized.as_ref().expect("ensured above");
        let group0 = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel aa group 0"),
            layout: &self.group0,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniforms.0.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: uniforms.1.as_entire_binding() },
            ],
        });
        let group1 = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel aa group 1"),
            layout: &self.group1,
            entries: &[
                self.params_entry(),
                Self::buffer(1, &self.edges),
                Self::buffer(2, &sized.map_words),
                Self::buffer(3, &sized.tile_words),
                Self::buffer(4, &sized.tile_list),
                Self::buffer(5, vertices),
                Self::buffer(6, indices),
                Self::buffer(7, &self.table),
                Self::buffer(8, &sized.occlusion),
                wgpu::BindGroupEntry { binding: 9, resource: wgpu::BindingResource::TextureView(masks) },
                wgpu::BindGroupEntry { binding: 10, resource: wgpu::BindingResource::TextureView(maps) },
            ],
        });
        let args_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel aa exact_args group"),
            layout: &self.args_group,
            entries: &[
                self.params_entry(),
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &sized.tile_words,
                        offset: 0,
                        size: wgpu::BufferSize::new(4 * STATS_WORDS),
                    }),
                },
                Self::buffer(2, &self.args),
            ],
        });
        encoder.clear_buffer(&sized.tile_words, 0, Some(4 * STATS_WORDS));
        for (i, m) in lights.iter().enumerate() {
            let (mw, mh) = (m.map_size.width, m.map_size.height);
            let (tx, ty) = (mw.div_ceil(TILE), mh.div_ceil(TILE));
            let raw = ParamsRaw {
                light: i as u32,
                tiles_x: tx,
                tiles_y: ty,
                capacity: self.capacity,
                width,
                height,
                edge_count: self.edge_count,
                triangle_count: triangles,
                bias: self.bias,
                sample_mask: samples.mask(),
                map_w: mw,
                map_h: mh,
                sat_base: sized.map_texels as u32,
                tile_stride: sized.tiles as u32,
                box_base: PAIR_CAPACITY,
                screen_base: PAIR_CAPACITY + 4 * sized.triangles as u32,
                queue_base: PAIR_CAPACITY + 8 * sized.triangles as u32,
                cull: u32::from(self.cull),
                valid_base: (pixels * lights.len() as u64) as u32,
                validity: u32::from(self.validity),
                uncertain: u32::from(self.uncertain),
                // As `ShadowPassRaw` passes it to the shadow pass.
                depth_bias: bias.constant as f32 * 2f32.powi(-24),
                slope_scale: bias.slope_scale,
                bias_clamp: bias.clamp,
                gate: u32::from(self.gate),
                depth_check: u32::from(self.depth_check),
                _pad: [0; 2],
            };
            queue.write_buffer(&self.params, i as u64 * PARAM_STRIDE, bytemuck::bytes_of(&raw));
            encoder.clear_buffer(&sized.map_words, 0, Some(4 * u64::from(mw) * u64::from(mh)));
            // Counts, cursors and forced flags (the offsets are all written
            // by the scan).
            encoder.clear_buffer(&sized.tile_words, 4 * STATS_WORDS, Some(8 * sized.tiles));
            encoder.clear_buffer(&sized.tile_words, 4 * (STATS_WORDS + 3 * sized.tiles), Some(4 * sized.tiles));
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&format!("lixel aa passes, light {i}")),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &group0, &[]);
            pass.set_bind_group(1, &group1, &[(i as u64 * PARAM_STRIDE) as u32]);
            let flat = |pass: &mut wgpu::ComputePass<'_>, entry: usize, n: u32| {
                pass.set_pipeline(&self.pipelines[entry]);
                let groups = n.div_ceil(GROUP).max(1);
                // 2D beyond the per-dimension limit (`flat_id` in the shader).
                let (x, y) = if groups <= 65_535 { (groups, 1) } else { (65_535, groups.div_ceil(65_535)) };
                pass.dispatch_workgroups(x, y, 1);
            };
            // The silhouette pass reads the shadow maps (its depth check). On
            // GL nothing orders a depth attachment's writes before a compute
            // read, and llvmpipe rasterizes in the background: the passes'
            // first dispatch could read a map still being drawn (seen: visible
            // silhouette texels dropped, and words differing between two
            // renders of one frame, in 3 of 9 GL runs of tests/render_aa.rs;
            // none in 6 runs with this dispatch). A storage write before it makes the
            // backend put a memory barrier between them (glMemoryBarrier,
            // which on llvmpipe waits for the rendering); elsewhere an
            // ordinary barrier between two dispatches.
            flat(&mut pass, 9, 1);
            flat(&mut pass, 0, self.edge_count);
            flat(&mut pass, 1, mh);
            flat(&mut pass, 2, mw);
            flat(&mut pass, 8, width * height);
            flat(&mut pass, 3, triangles);
            pass.set_pipeline(&self.pipelines[4]);
            pass.dispatch_workgroups(1, 1, 1);
            flat(&mut pass, 5, triangles);
            flat(&mut pass, 6, width * height);
            // Over the queue only: its length, known on the GPU, becomes the
            // dispatch's size (a dispatch over every pixel, the invocations
            // past the queue returning at once, cost 8% of the aa32 frame).
            pass.set_pipeline(&self.args_pipeline);
            pass.set_bind_group(0, &args_group, &[(i as u64 * PARAM_STRIDE) as u32]);
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_pipeline(&self.pipelines[7]);
            pass.set_bind_group(0, &group0, &[]);
            pass.set_bind_group(1, &group1, &[(i as u64 * PARAM_STRIDE) as u32]);
            pass.dispatch_workgroups_indirect(&self.args, i as u64 * ARGS_STRIDE);
        }
        self.last = Some(LastFrame { width, height, lights: lights.len(), capacity: self.capacity });
    }
}

impl Renderer {
    /// Light `light`'s occlusion words of the last frame rendered with
    /// [`ShadowLookup::SubPixelAa`](crate::render::ShadowLookup::SubPixelAa):
    /// one per camera pixel (row-major, row 0 at the top), bit `s` set when
    /// sub-sample `s` of [`SAMPLE_POSITIONS`] is
    /// occluded (only the pattern's bits). Pixels off the exact path hold
    /// their standard shadow bit in every sample bit. Blocks until done.
    ///
    /// # Errors
    /// [`RenderError::NothingRendered`] when no frame used the mode;
    /// [`RenderError::NoSuchLight`]; device, mapping or polling failures.
    pub fn read_occlusion(&self, light: usize) -> Result<Vec<u32>, RenderError> {
        let (last, sized) = self.aa_last()?;
        if light >= last.lights {
            return Err(RenderError::NoSuchLight { light, count: last.lights });
        }
        let pixels = u64::from(last.width) * u64::from(last.height);
        self.read_buffer_words(&sized.occlusion, light as u64 * pixels, pixels)
    }

    /// Light `light`'s validity words of the last frame rendered with
    /// [`ShadowLookup::SubPixelAa`](crate::render::ShadowLookup::SubPixelAa),
    /// one per camera pixel as [`read_occlusion`](Self::read_occlusion)'s:
    /// bit `s` set when sub-sample `s`'s facet point is seen by the camera,
    /// i.e. no triangle of the pixel's lists lies between them (the paper's
    /// validity mask) and, for a spot light, the facet point lies inside
    /// the cone (outside it a surface is unlit, not shadowed, as in the
    /// coverage truth). The pixel's visibility is the share of valid samples
    /// not occluded ([`bitmask::visibility_of_valid`](super::bitmask::visibility_of_valid)).
    /// Every pattern bit is set off the exact path and where none would be
    /// valid; where every sample is occluded, every bit in a spot's cone.
    /// Blocks until done.
    ///
    /// # Errors
    /// As [`read_occlusion`](Self::read_occlusion).
    pub fn read_validity(&self, light: usize) -> Result<Vec<u32>, RenderError> {
        let (last, sized) = self.aa_last()?;
        if light >= last.lights {
            return Err(RenderError::NoSuchLight { light, count: last.lights });
        }
        let pixels = u64::from(last.width) * u64::from(last.height);
        self.read_buffer_words(&sized.occlusion, (last.lights + light) as u64 * pixels, pixels)
    }

    /// The counts of the antialiased passes for light `light` of the last
    /// such frame.
    ///
    /// # Errors
    /// As [`read_occlusion`](Self::read_occlusion).
    pub fn read_aa_stats(&self, light: usize) -> Result<AaStats, RenderError> {
        let (last, sized) = self.aa_last()?;
        if light >= last.lights {
            return Err(RenderError::NoSuchLight { light, count: last.lights });
        }
        let w = self.read_buffer_words(&sized.tile_words, (light * STATS_PER_LIGHT) as u64, 9)?;
        Ok(AaStats {
            pairs: w[0],
            exact_pixels: w[1],
            overflow_pixels: w[2],
            wide_pixels: w[3],
            triangle_tests: w[4],
            uncertain_pixels: w[6],
            entries_scanned: w[7],
            silhouette_texels: w[8],
        })
    }

    /// Light `light`'s silhouette mask and summed-area table of the last
    /// antialiased frame (`map_size` texels each, row-major), for tests.
    ///
    /// # Errors
    /// As [`read_occlusion`](Self::read_occlusion). Only the last light's
    /// mask survives a frame (the buffers are reused per light).
    pub fn read_silhouette_mask(&self, light: usize) -> Result<(Vec<u32>, Vec<u32>), RenderError> {
        let (last, sized) = self.aa_last()?;
        if light + 1 != last.lights {
            return Err(RenderError::NoSuchLight { light, count: last.lights });
        }
        let m = &self.last_lights[light].map_size;
        let texels = u64::from(m.width) * u64::from(m.height);
        let mask = self.read_buffer_words(&sized.map_words, 0, texels)?;
        let sat = self.read_buffer_words(&sized.map_words, sized.map_texels, texels)?;
        Ok((mask, sat))
    }

    /// Light `light`'s triangle–tile lists of the last antialiased frame,
    /// for tests: per list tile of `LIST_TILE`² (4×4) texels, row-major
    /// (`map_width.div_ceil(LIST_TILE)` per row), the triangle indices it
    /// holds, sorted (the write order comes from atomics). A list whose
    /// entries did not fit in the capacity is `None` (its pixels keep the
    /// standard bit). Only the last light's lists survive a frame.
    ///
    /// # Errors
    /// As [`read_silhouette_mask`](Self::read_silhouette_mask).
    pub fn read_aa_lists(&self, light: usize) -> Result<Vec<Option<Vec<u32>>>, RenderError> {
        let (last, sized) = self.aa_last()?;
        if light + 1 != last.lights {
            return Err(RenderError::NoSuchLight { light, count: last.lights });
        }
        let m = &self.last_lights[light].map_size;
        let n = u64::from(m.width.div_ceil(LIST_TILE)) * u64::from(m.height.div_ceil(LIST_TILE));
        let counts = self.read_buffer_words(&sized.tile_words, STATS_WORDS, n)?;
        let offsets = self.read_buffer_words(&sized.tile_words, STATS_WORDS + 2 * sized.tiles, n)?;
        let total = counts.iter().map(|&c| u64::from(c)).sum::<u64>().min(u64::from(last.capacity));
        let entries = self.read_buffer_words(&sized.tile_list, 0, total)?;
        Ok(counts
            .iter()
            .zip(&offsets)
            .map(|(&count, &offset)| {
                let (start, end) = (offset as usize, offset as usize + count as usize);
                (end as u64 <= u64::from(last.capacity)).then(|| {
                    let mut list = entries[start..end].to_vec();
                    list.sort_unstable();
                    list
                })
            })
            .collect())
    }

    /// Side of the triangle–tile lists' tiles in map texels
    /// ([`read_aa_lists`](Self::read_aa_lists)).
    pub const AA_LIST_TILE: u32 = LIST_TILE;

    fn aa_last(&self) -> Result<(LastFrame, &Sized), RenderError> {
        let aa = self.aa.as_ref().ok_or(RenderError::NothingRendered)?;
        let last = aa.last.ok_or(RenderError::NothingRendered)?;
        let sized = aa.sized.as_ref().ok_or(RenderError::NothingRendered)?;
        Ok((last, sized))
    }

    /// `count` words of `buffer` from word `first`, after the queue's work.
    pub(in crate::render) fn read_buffer_words(
        &self,
        buffer: &wgpu::Buffer,
        first: u64,
        count: u64,
    ) -> Result<Vec<u32>, RenderError> {
        let size = 4 * count.max(1);
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel aa readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lixel aa readback") });
        encoder.copy_buffer_to_buffer(buffer, 4 * first, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let (sender, receiver) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |result| {
            let _ = sender.send(result);
        });
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        self.errors.take(&self.device, "reading back the antialiased passes")?;
        receiver.recv().map_err(|_| RenderError::Map(wgpu::BufferAsyncError))??;
        let words = {
            let view = staging.get_mapped_range(..).map_err(|_| RenderError::Map(wgpu::BufferAsyncError))?;
            bytemuck::cast_slice::<u8, u32>(&view)[..count as usize].to_vec()
        };
        staging.unmap();
        Ok(words)
    }

    /// Limits the triangle–tile lists to `entries` per light (clamped to
    /// `1..=`[`PAIR_CAPACITY`]; the default is the maximum), from the next
    /// frame on: a way to see the overflow policy at work.
    ///
    /// # Errors
    /// Device errors building the passes.
    pub fn set_aa_pair_capacity(&mut self, entries: u32) -> Result<(), RenderError> {
        self.ensure_aa()?;
        if let Some(aa) = self.aa.as_mut() {
            aa.capacity = entries.clamp(1, PAIR_CAPACITY);
        }
        Ok(())
    }

    /// Turns the per-pixel culling of list entries by the triangles' boxes
    /// off (`false`: every entry of a footprint's tiles is tested, as before
    /// the culling) or on (the default), from the next frame on: a way to
    /// compare both.
    ///
    /// # Errors
    /// Device errors building the passes.
    pub fn set_aa_footprint_culling(&mut self, on: bool) -> Result<(), RenderError> {
        self.ensure_aa()?;
        if let Some(aa) = self.aa.as_mut() {
            aa.cull = on;
        }
        Ok(())
    }

    /// Turns the validity mask of the antialiased lookup on (the default)
    /// or off (every sample valid: the facet's plane answers for the whole
    /// pixel; a spot light's samples outside its cone stay invalid), for
    /// comparisons.
    ///
    /// # Errors
    /// As [`set_aa_footprint_culling`](Self::set_aa_footprint_culling).
    pub fn set_aa_validity(&mut self, on: bool) -> Result<(), RenderError> {
        self.ensure_aa()?;
        if let Some(aa) = self.aa.as_mut() {
            aa.validity = on;
        }
        Ok(())
    }

    /// Turns the exact path for pixels whose depth compare is uncertain on
    /// (the default) or off (only pixels with a silhouette texel in the
    /// footprint take it), for comparisons.
    ///
    /// # Errors
    /// As [`set_aa_footprint_culling`](Self::set_aa_footprint_culling).
    pub fn set_aa_uncertain_pixels(&mut self, on: bool) -> Result<(), RenderError> {
        self.ensure_aa()?;
        if let Some(aa) = self.aa.as_mut() {
            aa.uncertain = on;
        }
        Ok(())
    }

    /// Turns the screen-box gate of the validity mask's hidden test on (the
    /// default) or off (every tested triangle runs the test), for
    /// comparisons: the words are the same either way.
    ///
    /// # Errors
    /// As [`set_aa_footprint_culling`](Self::set_aa_footprint_culling).
    pub fn set_aa_hidden_gate(&mut self, on: bool) -> Result<(), RenderError> {
        self.ensure_aa()?;
        if let Some(aa) = self.aa.as_mut() {
            aa.gate = on;
        }
        Ok(())
    }

    /// Turns the silhouette pass's depth check on (the default: a texel
    /// whose silhouette edges all lie behind the light's depth map in its
    /// 3x3 neighbourhood is not marked) or off (every texel a silhouette
    /// edge crosses is marked, as before the check), for comparisons.
    ///
    /// # Errors
    /// As [`set_aa_footprint_culling`](Self::set_aa_footprint_culling).
    pub fn set_aa_depth_check(&mut self, on: bool) -> Result<(), RenderError> {
        self.ensure_aa()?;
        if let Some(aa) = self.aa.as_mut() {
            aa.depth_check = on;
        }
        Ok(())
    }

    /// Builds the antialiased passes on first use.
    pub(crate) fn ensure_aa(&mut self) -> Result<(), RenderError> {
        if self.aa.is_none() {
            // The scene's positions and indices as uploaded (no CPU copy is
            // kept for a mode most renderers never use).
            let words = self.read_buffer_words(&self.scene.vertices, 0, self.scene.vertices.size() / 4)?;
            let positions = words
                .chunks_exact(7)
                .map(|v| glam::Vec3::new(f32::from_bits(v[0]), f32::from_bits(v[1]), f32::from_bits(v[2])));
            let mesh = Mesh {
                positions: positions.collect(),
                normals: Vec::new(),
                indices: self.read_buffer_words(&self.scene.indices, 0, u64::from(self.scene.index_count))?,
            };
            let bias = self.aa_bias;
            let aa = device::capture(&self.device, "antialiased passes", || AaPass::new(&self.device, &mesh, bias))?;
            self.aa = Some(aa);
        }
        Ok(())
    }
}
