//! Loading a user's scene file (OBJ or glTF 2.0) into a [`Scene`] that the
//! renderer, the ray caster and the solver can all use — or a typed error
//! that says what is wrong with the file.
//!
//! Users' meshes are scans, exports and hand edits: they carry polygons,
//! zero-area triangles, stray vertices, NaNs, odd up axes and sizes from
//! millimetres to kilometres. [`load_scene_file`] applies a fixed, documented
//! pipeline and reports every repair it made ([`LoadReport`]):
//!
//! 1. the file is sniffed: a directory, a binary file that is not glTF, or
//!    text that is not UTF-8 are refused by name; a UTF-8 byte-order mark is
//!    skipped; the format follows the extension (`.gltf`, `.glb`) or the
//!    `glTF` magic, anything else is OBJ;
//! 2. the triangle count is checked against [`MAX_TRIANGLES`] before the
//!    geometry is built;
//! 3. a NaN or infinite vertex is an error ([`SceneLoadError::NonFinite`]),
//!    so is a coordinate beyond [`MAX_COORDINATE`] after `--scale`;
//! 4. repairs: polygons are fan-triangulated, OBJ point and line elements
//!    ignored, glTF strips and fans unrolled and point/line primitives
//!    skipped, zero-area triangles dropped, unreferenced vertices dropped
//!    (so they cannot stretch the bounds), missing or invalid normals
//!    recomputed (area-weighted, smooth);
//! 5. [`SceneOptions::up`] turns a z-up file into the crate's y-up world and
//!    [`SceneOptions::scale`] scales it;
//! 6. what is left must have extent ([`SceneLoadError::AllVerticesCoincide`])
//!    and triangles; a model far from the origin for its size is moved to
//!    it before anything is rounded to single precision
//!    ([`Repair::Recentred`]); optionally a floor ([`Role::Receiver`]) is put
//!    under it so that the model's shadows have somewhere to fall.

use std::fmt;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};

use super::{gltf, obj, primitives, Mesh, MeshError, Role, Scene, SceneObject};
use crate::Aabb;

/// Most triangles a loaded scene may have. The experiment ray-casts every
/// pixel against all of them and draws them several times per
/// configuration; 5 M triangles (4.4× the paper's scene) is about 1.5 s per
/// pass on lavapipe and a few GiB of BVH and buffers. Bigger files are
/// refused before their geometry is built; decimate them first.
pub const MAX_TRIANGLES: usize = 5_000_000;

/// Largest coordinate magnitude a loaded vertex may have (after scaling).
/// The solver works in double precision but the renderer and the loaded
/// meshes in single precision; beyond about 1e15 the light and camera
/// matrices lose every digit of a scene's size.
pub const MAX_COORDINATE: f64 = 1e15;

/// How many floor triangles a loaded scene gets (a flat grid; enough for
/// smooth per-vertex lighting, few enough to cost nothing).
const FLOOR_TRIANGLES: usize = 2 * 16 * 16;

/// The floor's side, in bounding-sphere radii of the model: wide enough that
/// shadows of lights down to about 20° elevation land on it.
pub const FLOOR_SIZE_IN_RADII: f64 = 8.0;

/// Which file axis points up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum UpAxis {
    /// `+y` up (OBJ's usual convention and glTF's rule). No change.
    #[default]
    Y,
    /// `+z` up (CAD, Blender's own axes, many scans): `(x, y, z)` becomes
    /// `(x, z, -y)`, a right-handed rotation about `x`.
    Z,
}

/// How to turn a file into a scene.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SceneOptions {
    /// The file's up axis.
    pub up: UpAxis,
    /// Uniform scale applied to every vertex (after the up rotation). Must
    /// be positive and finite.
    pub scale: f64,
    /// Put a receiver-only floor under the model.
    pub floor: bool,
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self { up: UpAxis::Y, scale: 1.0, floor: true }
    }
}

/// Why a scene file could not be loaded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneLoadError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The path names a directory.
    #[error("{path} is a directory, not a scene file (give an .obj, .gltf or .glb file)")]
    IsDirectory {
        /// The path.
        path: PathBuf,
    },
    /// The file is binary (or not UTF-8) and not a glTF binary either.
    #[error("{path} is not a text OBJ file (binary data at byte {offset}); scenes are .obj, .gltf or .glb")]
    NotText {
        /// The file.
        path: PathBuf,
        /// Byte offset of the first non-text byte.
        offset: usize,
    },
    /// The OBJ parser failed.
    #[error(transparent)]
    Obj(#[from] obj::ObjError),
    /// The glTF reader failed.
    #[error(transparent)]
    Gltf(#[from] gltf::GltfError),
    /// More triangles than [`MAX_TRIANGLES`].
    #[error("{path} has {triangles} triangles, more than the limit of {limit}; decimate it first")]
    TooManyTriangles {
        /// The file.
        path: PathBuf,
        /// Its triangle count (at least this many).
        triangles: usize,
        /// [`MAX_TRIANGLES`].
        limit: usize,
    },
    /// An object's index or vertex lists are inconsistent.
    #[error("{path}: object {object:?}: {source}")]
    Geometry {
        /// The file.
        path: PathBuf,
        /// The object (OBJ `o`/`g` name, glTF mesh name).
        object: String,
        /// What is wrong.
        source: MeshError,
    },
    /// A vertex is NaN or infinite.
    #[error("{path}: object {object:?}: vertex {vertex} is not a finite number ({position})")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The object.
        object: String,
        /// Vertex index within the object.
        vertex: usize,
        /// The vertex as read.
        position: DVec3,
    },
    /// A vertex lies too far from the origin.
    #[error("{path}: object {object:?}: vertex {vertex} at {position} has coordinates beyond {limit:e}; move the model nearer the origin or --scale it down")]
    CoordinateRange {
        /// The file.
        path: PathBuf,
        /// The object.
        object: String,
        /// Vertex index within the object.
        vertex: usize,
        /// The vertex after scaling.
        position: DVec3,
        /// [`MAX_COORDINATE`].
        limit: f64,
    },
    /// `scale` is zero, negative or not finite.
    #[error("scale {scale} must be a positive finite number")]
    InvalidScale {
        /// The scale given.
        scale: f64,
    },
    /// The file holds no triangles at all.
    #[error("{path} holds no triangles")]
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
    /// Every triangle's vertices are one point: a zero-size mesh.
    #[error("{path}: all vertices coincide (at {point}); the mesh has no size")]
    AllVerticesCoincide {
        /// The file.
        path: PathBuf,
        /// The common point.
        point: DVec3,
    },
    /// Every triangle has zero area (collinear vertices).
    #[error("{path}: all {triangles} triangles have zero area")]
    AllDegenerate {
        /// The file.
        path: PathBuf,
        /// Triangles read.
        triangles: usize,
    },
}

/// One object as a file reader produced it, before repairs.
#[derive(Clone, Debug, Default)]
pub(crate) struct RawObject {
    pub name: String,
    /// Positions as read, in double precision (OBJ text is parsed to f64).
    pub positions: Vec<DVec3>,
    /// `None` when the file has none for this object.
    pub normals: Option<Vec<Vec3>>,
    pub indices: Vec<u32>,
}

/// What a reader returns: objects and the repairs it already made.
#[derive(Debug, Default)]
pub(crate) struct RawScene {
    pub objects: Vec<RawObject>,
    pub repairs: Vec<Repair>,
}

/// A repair [`load_scene_file`] made.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Repair {
    /// Polygons with more than three vertices, split into triangle fans.
    Triangulated {
        /// Polygons split.
        polygons: usize,
    },
    /// Faces or primitives that are points or lines, left out.
    IgnoredNonTriangles {
        /// Elements left out.
        count: usize,
    },
    /// glTF triangle strips and fans turned into triangle lists.
    UnrolledStripsAndFans {
        /// Primitives converted.
        primitives: usize,
    },
    /// Zero-area triangles (repeated or collinear vertices) dropped.
    DroppedDegenerate {
        /// Triangles dropped.
        triangles: usize,
    },
    /// Vertices no triangle uses, dropped.
    DroppedUnreferenced {
        /// Vertices dropped.
        vertices: usize,
    },
    /// Normals computed (missing, wrong count, zero or non-finite in the file).
    ComputedNormals {
        /// Objects whose normals were computed.
        objects: usize,
    },
    /// Objects left without triangles, dropped.
    DroppedEmptyObjects {
        /// Objects dropped.
        objects: usize,
    },
    /// The model lay far from the origin for its size (its centre farther
    /// than [`RECENTRE_BEYOND_DIAGONALS`] bounding diagonals): it was moved by `-offset` so that its
    /// centre is the origin. The renderer and the meshes work in single
    /// precision, whose step at a coordinate `c` is about `c * 6e-8`; a
    /// one-metre model 1 km away already loses sub-pixel shadow detail, and
    /// 100 km away whole shadows. Shadows do not depend on where the origin
    /// is; `--eye` and `--target` are in the moved coordinates.
    Recentred {
        /// The model's centre in the file (after up axis and scale), now
        /// the origin.
        offset: DVec3,
    },
}

impl fmt::Display for Repair {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Triangulated { polygons } => write!(f, "triangulated {polygons} polygons"),
            Self::IgnoredNonTriangles { count } => write!(f, "ignored {count} point/line elements"),
            Self::UnrolledStripsAndFans { primitives } => {
                write!(f, "unrolled {primitives} triangle strips/fans")
            }
            Self::DroppedDegenerate { triangles } => write!(f, "dropped {triangles} zero-area triangles"),
            Self::DroppedUnreferenced { vertices } => write!(f, "dropped {vertices} unused vertices"),
            Self::ComputedNormals { objects } => write!(f, "computed normals for {objects} objects"),
            Self::DroppedEmptyObjects { objects } => write!(f, "dropped {objects} objects without triangles"),
            Self::Recentred { offset } => write!(
                f,
                "moved by ({:.6}, {:.6}, {:.6}) to the origin for single precision (--eye/--target are in the moved coordinates)",
                -offset.x, -offset.y, -offset.z
            ),
        }
    }
}

/// What [`load_scene_file`] loaded.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadReport {
    /// Objects of the model (floor not included).
    pub objects: usize,
    /// Vertices of the model.
    pub vertices: usize,
    /// Triangles of the model.
    pub triangles: usize,
    /// Bounds of the model in the world (after up axis and scale).
    pub bounds: Aabb,
    /// Side of the floor added under it, if any.
    pub floor_size: Option<f64>,
    /// Every repair made, in pipeline order.
    pub repairs: Vec<Repair>,
}

impl fmt::Display for LoadReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (min, max) = (self.bounds.min, self.bounds.max);
        write!(
            f,
            "{} objects, {} vertices, {} triangles, bounds ({:.4}, {:.4}, {:.4})..({:.4}, {:.4}, {:.4})",
            self.objects, self.vertices, self.triangles, min.x, min.y, min.z, max.x, max.y, max.z
        )?;
        if let Some(size) = self.floor_size {
            write!(f, ", floor {size:.4} wide")?;
        }
        if self.repairs.is_empty() {
            write!(f, "; no repairs")
        } else {
            let list: Vec<String> = self.repairs.iter().map(ToString::to_string).collect();
            write!(f, "; repairs: {}", list.join(", "))
        }
    }
}

/// Loads an OBJ or glTF 2.0 file as a scene (see the module docs for every
/// step) and reports what it loaded.
///
/// # Errors
/// [`SceneLoadError`] naming the file and what is wrong.
pub fn load_scene_file(path: impl AsRef<Path>, options: &SceneOptions) -> Result<(Scene, LoadReport), SceneLoadError> {
    let path = path.as_ref();
    if !(options.scale > 0.0 && options.scale.is_finite()) {
        return Err(SceneLoadError::InvalidScale { scale: options.scale });
    }
    let io = |source| SceneLoadError::Io { path: path.into(), source };
    if std::fs::metadata(path).map_err(io)?.is_dir() {
        return Err(SceneLoadError::IsDirectory { path: path.into() });
    }
    let bytes = std::fs::read(path).map_err(io)?;
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let is_gltf = matches!(extension.as_deref(), Some("gltf" | "glb")) || bytes.starts_with(b"glTF");
    let raw = if is_gltf {
        gltf::read_gltf(&bytes, path, MAX_TRIANGLES)?
    } else {
        let text = obj_text(&bytes, path)?;
        let triangles = obj::count_triangles(text);
        if triangles > MAX_TRIANGLES {
            return Err(SceneLoadError::TooManyTriangles { path: path.into(), triangles, limit: MAX_TRIANGLES });
        }
        obj::read_obj(text, path)?
    };
    let triangles: usize = raw.objects.iter().map(|o| o.indices.len() / 3).sum();
    if triangles > MAX_TRIANGLES {
        return Err(SceneLoadError::TooManyTriangles { path: path.into(), triangles, limit: MAX_TRIANGLES });
    }
    build_scene(raw, path, options)
}

/// The text of an OBJ file: a byte-order mark skipped, binary refused.
fn obj_text<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a str, SceneLoadError> {
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let skipped = bytes.len() - body.len();
    let not_text = |offset| SceneLoadError::NotText { path: path.into(), offset: offset + skipped };
    let text = std::str::from_utf8(body).map_err(|e| not_text(e.valid_up_to()))?;
    // NUL and other control characters (tab, CR, LF and form feed aside) do not occur in OBJ text.
    if let Some(offset) = text.bytes().position(|b| b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0c)) {
        return Err(not_text(offset));
    }
    Ok(text)
}

/// Checks, repairs and transforms the reader's objects (steps 3 to 6).
fn build_scene(raw: RawScene, path: &Path, options: &SceneOptions) -> Result<(Scene, LoadReport), SceneLoadError> {
    let mut repairs = raw.repairs;
    let read_triangles: usize = raw.objects.iter().map(|o| o.indices.len() / 3).sum();
    if read_triangles == 0 {
        return Err(SceneLoadError::NoTriangles { path: path.into() });
    }
    // Every object's world positions and the bounds of what triangles use,
    // before anything is rounded to single precision.
    let mut placed = Vec::with_capacity(raw.objects.len());
    let mut all_bounds: Option<Aabb> = None;
    for object in raw.objects {
        let geometry = |source| SceneLoadError::Geometry { path: path.into(), object: object.name.clone(), source };
        if object.indices.len() % 3 != 0 {
            return Err(geometry(MeshError::PartialTriangle { count: object.indices.len() }));
        }
        if let Some(&index) = object.indices.iter().find(|&&i| i as usize >= object.positions.len()) {
            return Err(geometry(MeshError::IndexOutOfRange { index, vertices: object.positions.len() }));
        }
        let positions = world_positions(&object, path, options)?;
        let referenced = Aabb::from_points(object.indices.iter().map(|&i| positions[i as usize]));
        all_bounds = match (all_bounds, referenced) {
            (Some(a), Some(b)) => Some(a.union(&b)),
            (a, b) => a.or(b),
        };
        placed.push((object, positions));
    }
    let referenced = all_bounds.ok_or_else(|| SceneLoadError::NoTriangles { path: path.into() })?;
    if coincident(&referenced) {
        return Err(SceneLoadError::AllVerticesCoincide { path: path.into(), point: referenced.center() });
    }
    let offset = recentring_offset(&referenced);
    let (mut degenerate, mut unreferenced, mut computed, mut empty) = (0, 0, 0, 0);
    let mut objects = Vec::with_capacity(placed.len());
    for (object, mut positions) in placed {
        if let Some(offset) = offset {
            positions.iter_mut().for_each(|p| *p -= offset);
        }
        let (mesh, stats) = repaired_mesh(&object, &positions, options.up);
        degenerate += stats.degenerate;
        unreferenced += stats.unreferenced;
        computed += usize::from(stats.computed_normals);
        if mesh.triangle_count() == 0 {
            empty += 1;
            continue;
        }
        objects.push(SceneObject { name: object.name, mesh, role: Role::CasterAndReceiver, albedo: Vec3::splat(0.7) });
    }
    for (count, repair) in [
        (degenerate, Repair::DroppedDegenerate { triangles: degenerate }),
        (unreferenced, Repair::DroppedUnreferenced { vertices: unreferenced }),
        (computed, Repair::ComputedNormals { objects: computed }),
        (empty, Repair::DroppedEmptyObjects { objects: empty }),
    ] {
        if count > 0 {
            repairs.push(repair);
        }
    }
    if let Some(offset) = offset {
        repairs.push(Repair::Recentred { offset });
    }
    if objects.is_empty() {
        return Err(SceneLoadError::AllDegenerate { path: path.into(), triangles: read_triangles });
    }
    let mut scene = Scene { objects };
    let bounds = scene.bounds().casters;
    let report = LoadReport {
        objects: scene.objects.len(),
        vertices: scene.vertex_count(),
        triangles: scene.triangle_count(),
        bounds,
        floor_size: options.floor.then(|| add_floor(&mut scene, &bounds)),
        repairs,
    };
    Ok((scene, report))
}

/// How far from the origin, in bounding diagonals, a model's centre may lie
/// before it is moved there. Single precision then still resolves a
/// 1/10⁵ of the model's size; a model a few sizes off the origin (the usual
/// case) keeps the file's coordinates.
pub const RECENTRE_BEYOND_DIAGONALS: f64 = 16.0;

/// The model's centre when it lies farther from the origin than
/// [`RECENTRE_BEYOND_DIAGONALS`] (see [`Repair::Recentred`]).
fn recentring_offset(bounds: &Aabb) -> Option<DVec3> {
    let center = bounds.center();
    (center.length() > RECENTRE_BEYOND_DIAGONALS * bounds.diagonal()).then_some(center)
}

/// Whether every point of `bounds` is one point to single precision.
fn coincident(bounds: &Aabb) -> bool {
    let extent = (bounds.max - bounds.min).max_element();
    let magnitude = bounds.min.abs().max(bounds.max.abs()).max_element();
    extent <= 4.0 * f64::from(f32::EPSILON) * magnitude || extent == 0.0
}

/// The object's positions in the world (up axis, scale), checked.
fn world_positions(object: &RawObject, path: &Path, options: &SceneOptions) -> Result<Vec<DVec3>, SceneLoadError> {
    object
        .positions
        .iter()
        .enumerate()
        .map(|(vertex, &p)| {
            if !p.is_finite() {
                return Err(SceneLoadError::NonFinite {
                    path: path.into(),
                    object: object.name.clone(),
                    vertex,
                    position: p,
                });
            }
            let w = up_rotate(p, options.up) * options.scale;
            if w.abs().max_element() > MAX_COORDINATE {
                return Err(SceneLoadError::CoordinateRange {
                    path: path.into(),
                    object: object.name.clone(),
                    vertex,
                    position: w,
                    limit: MAX_COORDINATE,
                });
            }
            Ok(w)
        })
        .collect()
}

fn up_rotate(v: DVec3, up: UpAxis) -> DVec3 {
    match up {
        UpAxis::Y => v,
        UpAxis::Z => DVec3::new(v.x, v.z, -v.y),
    }
}

#[derive(Default)]
struct RepairStats {
    degenerate: usize,
    unreferenced: usize,
    computed_normals: bool,
}

/// The object without zero-area triangles and unused vertices, with
/// usable normals.
fn repaired_mesh(object: &RawObject, positions: &[DVec3], up: UpAxis) -> (Mesh, RepairStats) {
    let mut stats = RepairStats::default();
    let mut remap = vec![u32::MAX; positions.len()];
    let mut mesh = Mesh::default();
    let file_normals = object.normals.as_ref().filter(|n| n.len() == positions.len());
    let mut normals_ok = file_normals.is_some();
    for tri in object.indices.chunks_exact(3) {
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| positions[i as usize]);
        // Zero area in double precision or after rounding to the renderer's f32.
        let area2 = (b - a).cross(c - a).length();
        let [fa, fb, fc] = [a, b, c].map(|p| p.as_vec3());
        if !(area2 > 0.0) || !((fb - fa).cross(fc - fa).length() > 0.0) {
            stats.degenerate += 1;
            continue;
        }
        for &i in tri {
            let slot = &mut remap[i as usize];
            if *slot == u32::MAX {
                *slot = mesh.positions.len() as u32;
                mesh.positions.push(positions[i as usize].as_vec3());
                let n = file_normals.map_or(Vec3::Y, |n| up_rotate(n[i as usize].as_dvec3(), up).as_vec3());
                normals_ok &= n.is_finite() && n.length_squared() > 0.0;
                mesh.normals.push(n.normalize_or(Vec3::Y));
            }
            mesh.indices.push(*slot);
        }
    }
    stats.unreferenced = positions.len() - mesh.positions.len();
    if !normals_ok && mesh.triangle_count() > 0 {
        mesh.compute_smooth_normals();
        stats.computed_normals = true;
    }
    (mesh, stats)
}

/// Adds a receiver-only floor just under `bounds` ([`FLOOR_SIZE_IN_RADII`]
/// bounding radii wide, centred under the model); returns its side.
fn add_floor(scene: &mut Scene, bounds: &Aabb) -> f64 {
    let radius = 0.5 * bounds.diagonal();
    let size = FLOOR_SIZE_IN_RADII * radius;
    let center = bounds.center();
    // A hair below the model so that flat bottoms do not z-fight with it.
    let offset = DVec3::new(center.x, bounds.min.y - 1e-4 * radius, center.z);
    let mut mesh = primitives::floor(size as f32, FLOOR_TRIANGLES);
    for p in &mut mesh.positions {
        *p = (p.as_dvec3() + offset).as_vec3();
    }
    scene.objects.push(SceneObject {
        name: "floor".into(),
        mesh,
        role: Role::Receiver,
        albedo: Vec3::new(0.75, 0.72, 0.66),
    });
    size
}
