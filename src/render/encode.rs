//! Encoding one frame's passes: shadow passes into the lookup mode's maps,
//! the camera pass and the analysis pass with its copy into the readback
//! ring. [`Renderer::render`](super::Renderer::render) prepares the
//! resources and uniforms and calls these in order.

use super::capture::ViewCapture;
use super::lookup::{DepthClip, LookupState};
use super::uniforms::SHADOW_SLOT_STRIDE;
use super::{analysis, culling, timing, AnalysisSource, Renderer};
use crate::{Camera, LightMatrix};

/// Counts of one frame's shadow passes.
pub(crate) struct ShadowPassCounts {
    /// Maps that wanted unclipped depth the device lacks.
    pub(crate) unclipped_unavailable: u32,
    /// Triangles drawn, all passes together.
    pub(crate) triangles: u64,
    /// Passes drawn (the others were reused).
    pub(crate) passes: u32,
}

/// Whether the camera pass also writes the full-resolution masks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CameraOutput {
    /// Colour only.
    Color,
    /// Colour and masks.
    ColorAndMasks,
}

impl Renderer {
    /// One depth-only pass per slot into `state`'s maps, but for the slots
    /// whose layer already holds it (`reuse`; never with a timer).
    pub(crate) fn encode_shadow_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        state: &LookupState,
        slots: &[&LightMatrix],
        reuse: &[bool],
        timer: Option<&timing::FrameQueries>,
    ) -> ShadowPassCounts {
        let mut counts = ShadowPassCounts { unclipped_unavailable: 0, triangles: 0, passes: 0 };
        let last = slots.len().saturating_sub(1);
        for (i, m) in slots.iter().enumerate() {
            let wanted = if m.needs_unclipped_depth { DepthClip::Unclipped } else { DepthClip::Clipped };
            // Conservative rasterization draws its own (reshaped) triangles: no culling.
            let cull = if state.pulls_vertices { None } else { self.options.shadow_faces.cull(m) };
            let (pipeline, clip) = state.shadow.pipeline(wanted, cull);
            if clip != wanted {
                counts.unclipped_unavailable += 1;
            }
            if reuse.get(i).copied().unwrap_or(false) {
                continue;
            }
            counts.passes += 1;
            if let Some(centre) = state.maps.centre.as_ref().filter(|c| c.stride > 0) {
                // A drawn map's centre-sampled depths start empty (word 0);
                // a reused one keeps its own.
                encoder.clear_buffer(&centre.buffer, i as u64 * centre.stride, Some(centre.stride));
            }
            let timestamp_writes = self.timer.as_ref().zip(timer).and_then(|(t, q)| {
                // With SGSM the sweep ends the shadow stage.
                t.pass_writes(q, timing::Stage::Shadow, i == 0, i == last && state.sweep.is_none())
            });
            // A mode's colour layer starts cleared (zero words) like the depth.
            let sgsm_layer = state.maps.sgsm.as_ref().and_then(|s| s.normal_layers.get(i));
            let color_attachments: Vec<_> = state
                .maps
                .color_layers
                .get(i)
                .into_iter()
                .chain(sgsm_layer)
                .map(|view| wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
                .map(Some)
                .collect();
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&format!("lixel shadow pass {i}")),
                color_attachments: &color_attachments,
                // Far is 1: nothing blocks.
                depth_stencil_attachment: Some(depth_attachment(&state.maps.depth_layers[i])),
                timestamp_writes,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let (w, h) = (m.map_size.width, m.map_size.height);
            // Only the light's own rectangle at the top-left of the layer.
            pass.set_viewport(0.0, 0.0, w as f32, h as f32, 0.0, 1.0);
            pass.set_scissor_rect(0, 0, w, h);
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &state.shadow.bind_group, &[(i as u64 * SHADOW_SLOT_STRIDE) as u32]);
            if let Some(centre) = &state.maps.centre {
                pass.set_bind_group(1, &centre.pass_bind_group, &[(i as u64 * centre.stride) as u32]);
            }
            counts.triangles += if state.pulls_vertices {
                // The pass's own depth is never clipped at near and far.
                self.draw_pulled(&mut pass, &m.clip_from_world, DepthClip::Unclipped)
            } else {
                self.draw_scene(&mut pass, &self.scene.positions, &m.clip_from_world, clip)
            };
        }
        // SGSM: the sweep reads the finished maps.
        if let (Some(sweep), Some(maps)) = (&state.sweep, &state.maps.sgsm) {
            let sizes: Vec<_> = slots.iter().map(|m| (m.map_size.width, m.map_size.height)).collect();
            let writes = self.timer.as_ref().zip(timer).map(|(t, _)| t.compute_end_writes(timing::Stage::Shadow));
            sweep.encode(&self.queue, encoder, maps, &sizes, writes);
        }
        counts
    }

    /// [`draw_scene`](Self::draw_scene) for a pass that pulls its vertices:
    /// non-indexed draws whose `vertex_index` is the index slot.
    fn draw_pulled(&self, pass: &mut wgpu::RenderPass<'_>, clip_from_world: &glam::DMat4, clip: DepthClip) -> u64 {
        if !self.options.cull_objects {
            pass.draw(0..self.scene.index_count, 0..1);
            return u64::from(self.scene.index_count / 3);
        }
        let mut triangles = 0;
        for range in culling::visible_ranges(&self.scene.objects, clip_from_world, clip) {
            triangles += u64::from(range.len() as u32 / 3);
            pass.draw(range, 0..1);
        }
        triangles
    }

    /// Draws the scene, less the objects outside the clip volume of
    /// `clip_from_world` when [`RendererOptions::cull_objects`](super::RendererOptions::cull_objects)
    /// is set; returns the triangles drawn.
    /// `vertices` is the scene's full vertex buffer ([`VertexRaw::layout`](super::uniforms::VertexRaw::layout))
    /// or its packed positions (the shadow pass's
    /// [`position_layout`](super::uniforms::VertexRaw::position_layout)).
    fn draw_scene(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        vertices: &wgpu::Buffer,
        clip_from_world: &glam::DMat4,
        clip: DepthClip,
    ) -> u64 {
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        if !self.options.cull_objects {
            pass.draw_indexed(0..self.scene.index_count, 0, 0..1);
            return u64::from(self.scene.index_count / 3);
        }
        let mut triangles = 0;
        for range in culling::visible_ranges(&self.scene.objects, clip_from_world, clip) {
            triangles += u64::from(range.len() as u32 / 3);
            pass.draw_indexed(range, 0, 0..1);
        }
        triangles
    }

    pub(crate) fn encode_camera_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        state: &LookupState,
        camera: &Camera,
        output: CameraOutput,
        capture: Option<&ViewCapture>,
        timer: Option<&timing::FrameQueries>,
    ) -> u64 {
        let targets = self.camera_targets.as_ref().expect("created by ensure_resources");
        self.encode_camera_pass_into(encoder, state, &camera.clip_from_world(), targets, output, capture, timer)
    }

    /// The camera pass into `targets`, culling with `clip_from_world` (the
    /// supersampled mode's jittered passes draw into targets of their own;
    /// the camera uniforms must hold the same matrix).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn encode_camera_pass_into(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        state: &LookupState,
        clip_from_world: &glam::DMat4,
        targets: &super::passes::CameraTargets,
        output: CameraOutput,
        capture: Option<&ViewCapture>,
        timer: Option<&timing::FrameQueries>,
    ) -> u64 {
        let bg = self.options.background.as_dvec3();
        let mut color_attachments = vec![Some(wgpu::RenderPassColorAttachment {
            view: &targets.color.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color { r: bg.x, g: bg.y, b: bg.z, a: 1.0 }),
                store: wgpu::StoreOp::Store,
            },
        })];
        if output == CameraOutput::ColorAndMasks {
            color_attachments.push(Some(masks_attachment(&targets.masks.view)));
        }
        let timestamp_writes =
            self.timer.as_ref().zip(timer).and_then(|(t, q)| t.pass_writes(q, timing::Stage::Camera, true, true));
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lixel camera pass"),
            color_attachments: &color_attachments,
            depth_stencil_attachment: Some(depth_attachment(&targets.depth.view)),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.camera_bindings.bind_group, &[]);
        pass.set_bind_group(1, &state.maps.bind_group, &[]);
        if let (Some(capture), Some(deferred)) = (capture, state.camera.deferred_built()) {
            pass.set_pipeline(match output {
                CameraOutput::Color => &deferred.color,
                CameraOutput::ColorAndMasks => &deferred.color_masks,
            });
            pass.set_bind_group(2, &capture.bind_group, &[]);
            pass.draw(0..3, 0..1);
            return 0;
        }
        pass.set_pipeline(match output {
            CameraOutput::Color => &state.camera.color,
            CameraOutput::ColorAndMasks => &state.camera.color_masks,
        });
        self.draw_scene(&mut pass, &self.scene.vertices, clip_from_world, DepthClip::Clipped)
    }

    /// Draws the scene from the capture's camera into its targets (the
    /// camera uniforms already hold that camera).
    pub(crate) fn encode_capture_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        state: &LookupState,
        capture: &ViewCapture,
    ) {
        let targets = self.camera_targets.as_ref().expect("created by ensure_resources");
        let deferred = state.camera.deferred_built().expect("built by ensure_deferred");
        let attachments = capture.attachments();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lixel view capture pass"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(depth_attachment(&targets.depth.view)),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&deferred.capture);
        pass.set_bind_group(0, &self.camera_bindings.bind_group, &[]);
        self.draw_scene(&mut pass, &self.scene.vertices, &capture.camera.clip_from_world(), DepthClip::Clipped);
    }

    pub(crate) fn encode_analysis_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        state: &LookupState,
        camera: &Camera,
        staging: &wgpu::Buffer,
        timer: Option<&timing::FrameQueries>,
    ) {
        let timestamp_writes =
            self.timer.as_ref().zip(timer).and_then(|(t, q)| t.pass_writes(q, timing::Stage::Analysis, true, true));
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lixel analysis pass"),
                color_attachments: &[Some(masks_attachment(&self.analysis_masks.view))],
                depth_stencil_attachment: self.analysis_depth.as_ref().map(|t| depth_attachment(&t.view)),
                timestamp_writes,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, self.analysis_bind_group.as_ref(), &[]);
            pass.set_bind_group(1, &state.maps.bind_group, &[]);
            match self.options.analysis_source {
                AnalysisSource::CameraDepth => {
                    pass.set_pipeline(&state.analysis.depth);
                    pass.draw(0..3, 0..1);
                }
                AnalysisSource::Geometry => {
                    pass.set_pipeline(&state.analysis.geometry);
                    self.draw_scene(&mut pass, &self.scene.vertices, &camera.clip_from_world(), DepthClip::Clipped);
                }
            }
        }
        let (w, h) = self.options.analysis_size;
        encoder.copy_texture_to_buffer(
            self.analysis_masks.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(analysis::padded_row_bytes(w) as u32),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
    }
}

/// Masks attachment cleared to "background": depth 1.0's bits, no bits set.
fn masks_attachment(view: &wgpu::TextureView) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            // Integer targets take their clear value through f64; 1.0f32's
            // bits (0x3f80_0000) are exact in f64.
            load: wgpu::LoadOp::Clear(wgpu::Color { r: f64::from(1.0f32.to_bits()), g: 0.0, b: 0.0, a: 0.0 }),
            store: wgpu::StoreOp::Store,
        },
    }
}

/// Depth attachment cleared to the far value 1.
fn depth_attachment(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
        stencil_ops: None,
    }
}
