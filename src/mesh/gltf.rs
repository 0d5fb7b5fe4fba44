//! glTF 2.0 reading (`.gltf` with embedded or external buffers, `.glb`)
//! through the `gltf` crate: the default scene's node tree with its
//! transforms, every triangle primitive's positions, normals and indices.
//! Materials, textures, skins and animations are ignored — the experiment
//! needs geometry only.
//!
//! Buffers are resolved here rather than with `gltf::import` so that no
//! image decoders are compiled in and every failure becomes a
//! [`GltfError`] that names the file and the buffer.

use std::path::{Path, PathBuf};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use base64::Engine as _;
use glam::{DMat3, DMat4, DVec3, Mat4, Vec3};

use super::load::{RawObject, RawScene, Repair, SceneLoadError};

/// Deepest node hierarchy accepted (deeper is almost surely a cycle).
const MAX_NODE_DEPTH: usize = 256;

/// Why a glTF file could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GltfError {
    /// Not valid glTF (JSON, GLB container or the glTF schema).
    #[error("{path} is not a valid glTF 2.0 file: {source}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The `gltf` crate's error.
        source: ::gltf::Error,
    },
    /// A buffer is missing, unreadable or shorter than declared.
    #[error("{path}: buffer {index}: {reason}")]
    Buffer {
        /// The file.
        path: PathBuf,
        /// The buffer's index.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// An attribute has a type the reader does not take (positions must be
    /// float vec3, normals float vec3).
    #[error("{path}: mesh {mesh:?}: {attribute} is {found}, expected float VEC3")]
    AttributeType {
        /// The file.
        path: PathBuf,
        /// The mesh.
        mesh: String,
        /// `POSITION` or `NORMAL`.
        attribute: &'static str,
        /// The accessor's type.
        found: String,
    },
    /// The node tree is deeper than a tree plausibly is (a cycle).
    #[error("{path}: the node hierarchy is deeper than {MAX_NODE_DEPTH} levels (a cycle?)")]
    Hierarchy {
        /// The file.
        path: PathBuf,
    },
}

/// One primitive to read, with its world transform.
struct Instance<'a> {
    primitive: ::gltf::Primitive<'a>,
    mesh_name: String,
    transform: DMat4,
}

/// Reads `bytes` (the file at `path`) into raw objects, one per mesh
/// primitive instance, in world space. Refuses more than `max_triangles`
/// before reading any vertex.
pub(crate) fn read_gltf(bytes: &[u8], path: &Path, max_triangles: usize) -> Result<RawScene, SceneLoadError> {
    let gltf = ::gltf::Gltf::from_slice(bytes).map_err(|source| GltfError::Parse { path: path.into(), source })?;
    let document = &gltf.document;

    let mut instances = Vec::new();
    match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => {
            for root in scene.nodes() {
                visit(&mut instances, root, DMat4::IDENTITY, 0, path)?;
            }
        }
        // No scene at all: every mesh once, untransformed.
        None => {
            for mesh in document.meshes() {
                push_mesh(&mut instances, &mesh, DMat4::IDENTITY);
            }
        }
    }

    let mut repairs = Vec::new();
    let (mut skipped, mut unrolled) = (0, 0);
    let mut triangles = 0usize;
    for instance in &instances {
        triangles += match instance.primitive.mode() {
            Mode::Triangles => index_count(&instance.primitive) / 3,
            Mode::TriangleStrip | Mode::TriangleFan => index_count(&instance.primitive).saturating_sub(2),
            _ => 0,
        };
    }
    if triangles > max_triangles {
        return Err(SceneLoadError::TooManyTriangles { path: path.into(), triangles, limit: max_triangles });
    }

    let buffers = load_buffers(&gltf, path)?;
    let mut objects = Vec::with_capacity(instances.len());
    for instance in instances {
        let mode = instance.primitive.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            skipped += 1;
            continue;
        }
        unrolled += usize::from(mode != Mode::Triangles);
        let Some(object) = read_primitive(&instance, &buffers, path)? else {
            skipped += 1;
            continue;
        };
        objects.push(object);
    }
    if skipped > 0 {
        repairs.push(Repair::IgnoredNonTriangles { count: skipped });
    }
    if unrolled > 0 {
        repairs.push(Repair::UnrolledStripsAndFans { primitives: unrolled });
    }
    Ok(RawScene { objects, repairs })
}

fn visit<'a>(
    instances: &mut Vec<Instance<'a>>,
    node: ::gltf::Node<'a>,
    parent: DMat4,
    depth: usize,
    path: &Path,
) -> Result<(), GltfError> {
    if depth > MAX_NODE_DEPTH {
        return Err(GltfError::Hierarchy { path: path.into() });
    }
    let transform = parent * Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
    if let Some(mesh) = node.mesh() {
        push_mesh(instances, &mesh, transform);
    }
    for child in node.children() {
        visit(instances, child, transform, depth + 1, path)?;
    }
    Ok(())
}

fn push_mesh<'a>(instances: &mut Vec<Instance<'a>>, mesh: &::gltf::Mesh<'a>, transform: DMat4) {
    let name = mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_owned);
    for primitive in mesh.primitives() {
        instances.push(Instance { primitive, mesh_name: name.clone(), transform });
    }
}

/// Vertices the primitive's index list (or vertex list) names.
fn index_count(primitive: &::gltf::Primitive) -> usize {
    primitive.indices().or_else(|| primitive.get(&::gltf::Semantic::Positions)).map_or(0, |a| a.count())
}

fn check_vec3(
    accessor: &::gltf::Accessor,
    instance: &Instance,
    attribute: &'static str,
    path: &Path,
) -> Result<(), GltfError> {
    if accessor.data_type() == DataType::F32 && accessor.dimensions() == Dimensions::Vec3 {
        return Ok(());
    }
    Err(GltfError::AttributeType {
        path: path.into(),
        mesh: instance.mesh_name.clone(),
        attribute,
        found: format!("{:?} {:?}", accessor.data_type(), accessor.dimensions()),
    })
}

/// One primitive in world space; `None` without positions.
fn read_primitive(instance: &Instance, buffers: &[Vec<u8>], path: &Path) -> Result<Option<RawObject>, GltfError> {
    let primitive = &instance.primitive;
    let Some(position_accessor) = primitive.get(&::gltf::Semantic::Positions) else { return Ok(None) };
    check_vec3(&position_accessor, instance, "POSITION", path)?;
    if let Some(normals) = primitive.get(&::gltf::Semantic::Normals) {
        check_vec3(&normals, instance, "NORMAL", path)?;
    }
    let reader = primitive.reader(|buffer| buffers.get(buffer.index()).map(Vec::as_slice));
    let Some(positions) = reader.read_positions() else { return Ok(None) };
    let m = instance.transform;
    let positions: Vec<DVec3> = positions.map(|p| m.transform_point3(Vec3::from_array(p).as_dvec3())).collect();
    let normal_matrix = DMat3::from_mat4(m).inverse().transpose();
    let normals = reader.read_normals().map(|n| {
        n.map(|n| (normal_matrix * Vec3::from_array(n).as_dvec3()).normalize_or_zero().as_vec3()).collect::<Vec<_>>()
    });
    let list: Vec<u32> = match reader.read_indices() {
        Some(indices) => indices.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    let mut indices = match primitive.mode() {
        Mode::TriangleStrip => (2..list.len())
            .flat_map(|i| {
                if i % 2 == 0 {
                    [list[i - 2], list[i - 1], list[i]]
                } else {
                    [list[i - 1], list[i - 2], list[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..list.len()).flat_map(|i| [list[0], list[i - 1], list[i]]).collect(),
        _ => list,
    };
    // A mirroring transform flips the winding; keep triangles counter-clockwise.
    if DMat3::from_mat4(m).determinant() < 0.0 {
        for tri in indices.chunks_exact_mut(3) {
            tri.swap(1, 2);
        }
    }
    let name = format!("{} #{}", instance.mesh_name, primitive.index());
    Ok(Some(RawObject { name, positions, normals, indices }))
}

/// Every buffer's bytes: the GLB blob, a `data:` URI or a file beside the glTF.
fn load_buffers(gltf: &::gltf::Gltf, path: &Path) -> Result<Vec<Vec<u8>>, GltfError> {
    let mut buffers = Vec::new();
    for buffer in gltf.document.buffers() {
        let index = buffer.index();
        let fail = |reason: String| GltfError::Buffer { path: path.into(), index, reason };
        let data = match buffer.source() {
            ::gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| fail("no binary chunk".into()))?,
            ::gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (header, payload) = rest.split_once(',').ok_or_else(|| fail("malformed data URI".into()))?;
                    if !header.ends_with(";base64") {
                        return Err(fail("data URI is not base64".into()));
                    }
                    base64::engine::general_purpose::STANDARD
                        .decode(payload)
                        .map_err(|e| fail(format!("bad base64: {e}")))?
                } else {
                    let file = path.parent().unwrap_or(Path::new(".")).join(percent_decode(uri));
                    std::fs::read(&file).map_err(|e| fail(format!("cannot read {}: {e}", file.display())))?
                }
            }
        };
        if data.len() < buffer.length() {
            return Err(fail(format!("{} bytes, {} declared", data.len(), buffer.length())));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// `%XX` escapes of a relative URI decoded (malformed escapes kept as written).
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
        match (bytes[i], hex.and_then(|h| u8::from_str_radix(h, 16).ok())) {
            (b'%', Some(b)) => {
                out.push(b);
                i += 3;
            }
            (b, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}
