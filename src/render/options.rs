//! The renderer's settings: depth bias, faces drawn into shadow maps,
//! where the analysis pass gets its surface, and the options fixed at
//! creation.

use glam::Vec3;

use crate::LightMatrix;

/// The depth bias of every shadow map, the same for every method.
///
/// Shadow maps store *linear* light depth (distance along the light's rays,
/// normalized to the matrix's [`LightDistance`](crate::LightDistance) range;
/// see `shaders/shadow.wgsl`), and `fs_shadow` adds
/// `slope_scale · m + constant · 2⁻²⁴` to it, where
/// `m = max(|∂z/∂x|, |∂z/∂y|)` is the stored depth's slope per texel,
/// clamped to `clamp` when that is non-zero. A receiver looked up at most half
/// a texel from a texel centre differs from the stored depth by at most `m`
/// on a plane, so `slope_scale >= 1` prevents self-shadowing of planar
/// surfaces; `2` leaves room. Because the depth is linear, `m` depends only
/// on the surface's angle to the light rays and the texel's size, never on
/// how a warped map spends its projective depth. No normal offset is used at
/// lookup, so the only method-dependent effect is each map's own texel size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowBias {
    /// In units of the smallest depth step `r`.
    pub constant: i32,
    /// Multiple of the depth slope per texel.
    pub slope_scale: f32,
    /// Largest bias in depth units; 0 for none.
    pub clamp: f32,
}

impl Default for ShadowBias {
    fn default() -> Self {
        Self { constant: 16, slope_scale: 2.0, clamp: 0.0 }
    }
}

/// Which faces the shadow pass draws.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowFaces {
    /// Every triangle (works for open and inconsistently wound meshes; needs
    /// the slope-scaled [`ShadowBias`] against self-shadowing).
    #[default]
    Both,
    /// Only triangles facing away from the light ("second-depth" shadow
    /// maps, Wang & Molnar 1994): lit surfaces are compared with the far side
    /// of their occluders, so no slope-scaled bias is needed and edge-on
    /// casters are never pushed behind their receivers. Needs closed meshes
    /// wound counter-clockwise seen from outside (the procedural scene's).
    /// Mirrored light matrices are detected (`det(clip_from_world) < 0`) and
    /// cull the other winding.
    AwayFromLight,
}

impl ShadowFaces {
    /// The faces the shadow pass of `m` culls.
    pub(crate) fn cull(self, m: &LightMatrix) -> Option<wgpu::Face> {
        match self {
            Self::Both => None,
            Self::AwayFromLight => Some(away_from_light_cull(m)),
        }
    }
}

/// The winding cull that keeps only faces turned away from the light of `m`:
/// a small triangle facing the light is projected by `m`, and by a standard
/// camera a triangle facing that camera (whose front faces are
/// counter-clockwise in wgpu); the same sign of their signed areas means the
/// light sees its facing triangles as front faces, which are then culled.
/// (The 4x4 determinant does not decide this: the depth row's sign enters it
/// but not the 2D winding.)
fn away_from_light_cull(m: &LightMatrix) -> wgpu::Face {
    let centre = m.clip_from_world.inverse().project_point3(glam::DVec3::new(0.0, 0.0, 0.5));
    let towards_light = match m.frame {
        crate::LightFrame::Perspective { position, .. } => position - centre,
        crate::LightFrame::Orthographic { rotation } => -rotation.row(2),
    };
    let light = facing_winding(&m.clip_from_world, centre, towards_light);
    let view = glam::dcamera::rh::view::look_at_mat4(glam::DVec3::Z, glam::DVec3::ZERO, glam::DVec3::Y);
    let proj = glam::dcamera::rh::proj::directx::perspective(1.0, 1.0, 0.1, 10.0);
    let reference = facing_winding(&(proj * view), glam::DVec3::ZERO, glam::DVec3::Z);
    if light * reference > 0.0 {
        wgpu::Face::Front
    } else {
        wgpu::Face::Back
    }
}

/// Signed NDC area of a small triangle at `p` whose counter-clockwise
/// (outward) side faces `towards`, projected by `m`.
fn facing_winding(m: &glam::DMat4, p: glam::DVec3, towards: glam::DVec3) -> f64 {
    let n = towards.normalize_or(glam::DVec3::Y);
    let (t1, t2) = n.any_orthonormal_pair();
    // (t1, t2, n) right-handed, so p, p + t1, p + t2 is CCW seen from n.
    let (t1, t2) = if t1.cross(t2).dot(n) > 0.0 { (t1, t2) } else { (t2, t1) };
    let size = 1e-3 * p.length().max(1.0);
    let project = |q: glam::DVec3| m.project_point3(q).truncate();
    let (a, b, c) = (project(p), project(p + t1 * size), project(p + t2 * size));
    (b - a).perp_dot(c - a)
}

/// Where the analysis pass gets the visible surface from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AnalysisSource {
    /// A full-screen pass over the camera pass's depth buffer and masks (no
    /// second geometry pass; its cost does not grow with the scene). Each
    /// analysis pixel stands for the full-resolution point at its scaled
    /// centre: the depth there is extrapolated from the nearest
    /// full-resolution pixel along the one-sided depth differences that
    /// continue its surface (exact on planes, where screen-space depth is
    /// affine). Lights whose analysis map is the frame's own take that
    /// pixel's shadow and facing bits from the camera pass, which then writes
    /// its masks on analysis frames; others (the periodic focused maps) are
    /// looked up at the world point reconstructed from the 32-bit depth, with
    /// the camera pass's interpolated normal.
    #[default]
    CameraDepth,
    /// Draws the scene again at the analysis resolution, with interpolated
    /// positions and vertex normals. Exact, but on a software rasterizer it
    /// costs a good part of a camera pass.
    Geometry,
}

/// Settings fixed when the renderer is created.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RendererOptions {
    /// Resolution of the analysis pass (the paper: 180x180 for 1150² screens).
    pub analysis_size: (u32, u32),
    /// Where the analysis pass gets the visible surface from.
    pub analysis_source: AnalysisSource,
    /// Staging buffers of the analysis readback ring (the paper used 2).
    pub readback_slots: usize,
    /// Shadow-map depth bias.
    pub bias: ShadowBias,
    /// Which faces the shadow pass rasterizes.
    pub shadow_faces: ShadowFaces,
    /// Light that reaches every surface regardless of shadows, in `[0, 1]`.
    pub ambient: f32,
    /// Clear colour of the camera pass (linear RGB).
    pub background: Vec3,
    /// Record GPU timestamps when the device supports them.
    pub timestamps: bool,
    /// Leave out of each scene pass the objects whose bounding box lies
    /// outside its clip volume (the output is the same; see
    /// [`FrameReport::shadow_triangles`](super::FrameReport::shadow_triangles)).
    pub cull_objects: bool,
    /// Skip a shadow pass whose layer still holds what it would draw: the
    /// same matrix and uniforms as the last pass into that layer of the same
    /// lookup mode's maps (a pass is a pure function of them, so the output
    /// is the same; see [`FrameReport::maps_reused`](super::FrameReport::maps_reused)).
    /// Not for frames with GPU timestamps (which time every pass) nor SGSM
    /// (its sweep follows the passes); off by default.
    pub reuse_maps: bool,
    /// SPSM and SGSM passes: let the rasterizer's conservative mode
    /// (`wgpu::Features::CONSERVATIVE_RASTERIZATION`, overestimation) find the
    /// texels a triangle touches where the device has it, instead of the
    /// vertex stage's padded triangle; the fragment stage's exact texel test
    /// is the same, so the maps should be too (issue 16). Off by default: no
    /// adapter lixel has run on offers the feature (lavapipe, llvmpipe GL),
    /// so "both give the same maps" (`render_spsm`'s
    /// `hardware_conservative_maps_match_the_shader_path`) has not been shown
    /// yet. Ignored where the device lacks the feature.
    pub hardware_conservative: bool,
}

impl Default for RendererOptions {
    fn default() -> Self {
        Self {
            analysis_size: (180, 180),
            analysis_source: AnalysisSource::CameraDepth,
            readback_slots: 3,
            bias: ShadowBias::default(),
            shadow_faces: ShadowFaces::Both,
            ambient: 0.25,
            background: Vec3::new(0.55, 0.68, 0.85),
            timestamps: true,
            cull_objects: true,
            reuse_maps: false,
            hardware_conservative: false,
        }
    }
}
