//! Triangle meshes and scenes: the geometry the renderer draws and the CPU
//! ray caster tests against.
//!
//! Everything here is CPU-only (no wgpu), in single precision, in the crate's
//! world conventions (right-handed, `y` up for the built-in scenes).
//!
//! * [`Mesh`]: positions, per-vertex normals and a triangle list.
//! * [`Scene`]: meshes with a [`Role`] (receiver only, or caster and
//!   receiver) and a colour; [`Scene::bounds`] feeds [`crate::ShadowProblem`].
//! * [`procedural`]: the built-in test scene of the paper (a few dozen
//!   objects on or near a floor) at any triangle budget.
//! * [`obj`]: Wavefront OBJ loading with typed errors.
//! * [`load`]: users' scene files (OBJ or glTF 2.0, see [`mod@gltf`]) checked,
//!   repaired, oriented and scaled, with a floor under them if asked for.
//! * [`raycast`]: a BVH and exact shadow rays, the ground truth for
//!   shadow tests.
//! * [`masks`]: per-pixel shadow and light-facing bits, as the renderer reads
//!   them back and the ray caster traces them.

pub mod gltf;
pub mod load;
pub mod masks;
pub mod obj;
pub mod primitives;
pub mod procedural;
pub mod raycast;

use glam::{Affine3A, Vec3};

pub use load::{
    load_scene_file, LoadReport, Repair, SceneLoadError, SceneOptions, UpAxis, MAX_COORDINATE, MAX_TRIANGLES,
    RECENTRE_BEYOND_DIAGONALS,
};
pub use masks::{Flicker, MaskAgreement, ShadowMasks};
pub use obj::{load_obj, ObjError};
pub use procedural::{default_scene, ProceduralScene};
pub use raycast::{Bvh, PrimaryView, RayCaster};

use crate::{Aabb, SceneBounds};

/// Why a mesh or scene cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// `positions` and `normals` differ in length.
    #[error("mesh has {positions} positions but {normals} normals")]
    NormalCountMismatch {
        /// Number of positions.
        positions: usize,
        /// Number of normals.
        normals: usize,
    },
    /// The index list is not a whole number of triangles.
    #[error("index count {count} is not a multiple of 3")]
    PartialTriangle {
        /// Number of indices.
        count: usize,
    },
    /// An index points past the end of the vertex list.
    #[error("index {index} out of range for {vertices} vertices")]
    IndexOutOfRange {
        /// The offending index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A position or normal is NaN or infinite.
    #[error("non-finite vertex {vertex}")]
    NonFinite {
        /// Index of the offending vertex.
        vertex: usize,
    },
    /// The scene has no triangles at all.
    #[error("the scene has no triangles")]
    Empty,
    /// The scene has more vertices than a `u32` index can address.
    #[error("the scene has {vertices} vertices, more than 32-bit indices can address")]
    TooManyVertices {
        /// Total vertex count.
        vertices: usize,
    },
}

/// An indexed triangle mesh with per-vertex normals.
///
/// Triangles are counter-clockwise seen from the side their normals point to
/// (wgpu's default front face).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Triangle list: three indices per triangle.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Checks lengths, index ranges and finiteness.
    ///
    /// # Errors
    /// The first problem found, as a [`MeshError`].
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.positions.len() != self.normals.len() {
            return Err(MeshError::NormalCountMismatch {
                positions: self.positions.len(),
                normals: self.normals.len(),
            });
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(MeshError::PartialTriangle { count: self.indices.len() });
        }
        if let Some(&index) = self.indices.iter().find(|&&i| i as usize >= self.positions.len()) {
            return Err(MeshError::IndexOutOfRange { index, vertices: self.positions.len() });
        }
        if let Some(vertex) =
            self.positions.iter().zip(&self.normals).position(|(p, n)| !(p.is_finite() && n.is_finite()))
        {
            return Err(MeshError::NonFinite { vertex });
        }
        Ok(())
    }

    /// The mesh with every vertex moved by `transform` (normals by its
    /// inverse transpose, renormalised).
    #[must_use]
    pub fn transformed(mut self, transform: &Affine3A) -> Self {
        let normal_matrix = transform.matrix3.inverse().transpose();
        for p in &mut self.positions {
            *p = transform.transform_point3(*p);
        }
        for n in &mut self.normals {
            *n = (normal_matrix * *n).normalize_or_zero();
        }
        self
    }

    /// Appends `other`'s triangles.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// Bounds of the vertices; `None` for an empty mesh.
    #[must_use]
    pub fn bounds(&self) -> Option<Aabb> {
        Aabb::from_points(self.positions.iter().map(|p| p.as_dvec3()))
    }

    /// Replaces the normals by area-weighted face normals averaged at each
    /// vertex (for meshes loaded without normals).
    pub fn compute_smooth_normals(&mut self) {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        for tri in self.indices.chunks_exact(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| self.positions[i as usize]);
            // Cross product length is twice the area: area weighting for free.
            let n = (b - a).cross(c - a);
            for &i in tri {
                normals[i as usize] += n;
            }
        }
        self.normals = normals.into_iter().map(|n| n.normalize_or(Vec3::Y)).collect();
    }
}

/// What an object does in the shadow computation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Role {
    /// Shows shadows but casts none worth mapping (a floor under everything).
    /// It is still drawn into shadow maps; the role only shapes
    /// [`Scene::bounds`].
    Receiver,
    /// Casts and receives shadows.
    CasterAndReceiver,
}

/// One mesh in a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneObject {
    /// A name for reports.
    pub name: String,
    /// The geometry, in world space.
    pub mesh: Mesh,
    /// Its role for [`Scene::bounds`].
    pub role: Role,
    /// Linear RGB albedo in `[0, 1]`.
    pub albedo: Vec3,
}

/// A set of world-space meshes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// The objects.
    pub objects: Vec<SceneObject>,
}

impl Scene {
    /// Total triangle count.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.triangle_count()).sum()
    }

    /// Total vertex count.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.positions.len()).sum()
    }

    /// Validates every mesh and the total size.
    ///
    /// # Errors
    /// [`MeshError::Empty`] without triangles, [`MeshError::TooManyVertices`]
    /// past `u32` indexing, or the first mesh's own error.
    pub fn validate(&self) -> Result<(), MeshError> {
        for object in &self.objects {
            object.mesh.validate()?;
        }
        if self.triangle_count() == 0 {
            return Err(MeshError::Empty);
        }
        let vertices = self.vertex_count();
        if u32::try_from(vertices).is_err() {
            return Err(MeshError::TooManyVertices { vertices });
        }
        Ok(())
    }

    /// Casters and receivers for the solver: receiver-only objects (the
    /// floor) go into the receiver box only; the others into both.
    ///
    /// A scene without casters reports the receiver box for both (a valid,
    /// if pointless, problem). An empty scene gives a unit box at the origin.
    #[must_use]
    pub fn bounds(&self) -> SceneBounds {
        let union = |role: Option<Role>| {
            self.objects
                .iter()
                .filter(|o| role.is_none_or(|r| o.role == r))
                .filter_map(|o| o.mesh.bounds())
                .reduce(|a, b| a.union(&b))
        };
        let receivers =
            union(None).unwrap_or_else(|| Aabb::from_corners(glam::DVec3::splat(-0.5), glam::DVec3::splat(0.5)));
        let casters = union(Some(Role::CasterAndReceiver)).unwrap_or(receivers);
        SceneBounds { casters, receivers }
    }

    /// All objects as one mesh (vertex order: object by object), with the
    /// index of the object each triangle came from.
    #[must_use]
    pub fn merged(&self) -> (Mesh, Vec<u32>) {
        let mut mesh = Mesh {
            positions: Vec::with_capacity(self.vertex_count()),
            normals: Vec::with_capacity(self.vertex_count()),
            indices: Vec::with_capacity(3 * self.triangle_count()),
        };
        let mut triangle_object = Vec::with_capacity(self.triangle_count());
        for (k, object) in self.objects.iter().enumerate() {
            mesh.append(&object.mesh);
            triangle_object.extend(std::iter::repeat_n(k as u32, object.mesh.triangle_count()));
        }
        (mesh, triangle_object)
    }
}
