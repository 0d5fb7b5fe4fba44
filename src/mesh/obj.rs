//! Wavefront OBJ loading (through `tobj`), with errors that say which file
//! and what went wrong.

use std::io::BufRead;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};

use super::load::{RawObject, RawScene, Repair};
use super::{Mesh, MeshError, Role, Scene, SceneObject};

/// Why an OBJ file could not be loaded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ObjError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is not valid OBJ.
    #[error("{path} is not a valid OBJ file: {source}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's error.
        source: tobj::LoadError,
    },
    /// The file parsed but its geometry is unusable (indices out of range,
    /// NaN coordinates, ...).
    #[error("{path}: object {object:?}: {source}")]
    Geometry {
        /// The file.
        path: PathBuf,
        /// The OBJ object (`o`/`g` name) at fault.
        object: String,
        /// What is wrong.
        source: MeshError,
    },
    /// The file holds no triangles.
    #[error("{path} holds no triangles")]
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
}

/// Loads every object of an OBJ file as a caster-and-receiver with a
/// neutral albedo. Polygons are triangulated; missing normals are computed
/// (area-weighted, smooth); materials and texture coordinates are ignored.
///
/// # Errors
/// [`ObjError`] naming the file and the problem.
pub fn load_obj(path: impl AsRef<Path>) -> Result<Scene, ObjError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|source| ObjError::Io { path: path.into(), source })?;
    load_obj_reader(&mut std::io::BufReader::new(file), path)
}

/// Like [`load_obj`], from any reader; `path` is only used in errors.
///
/// # Errors
/// [`ObjError`] naming `path` and the problem.
pub fn load_obj_reader(reader: &mut impl BufRead, path: impl AsRef<Path>) -> Result<Scene, ObjError> {
    let path = path.as_ref();
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
    // Materials are not used: report every `mtllib` as absent.
    let (models, _materials) = tobj::load_obj_buf(reader, &options, |_| Err(tobj::LoadError::OpenFileFailed))
        .map_err(|source| ObjError::Parse { path: path.into(), source })?;
    let mut objects = Vec::with_capacity(models.len());
    for model in models {
        let m = model.mesh;
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(|p| DVec3::from_slice(p).as_vec3()).collect();
        let has_normals = m.normals.len() == m.positions.len();
        let mut mesh = Mesh {
            normals: if has_normals {
                m.normals.chunks_exact(3).map(|n| DVec3::from_slice(n).as_vec3().normalize_or(Vec3::Y)).collect()
            } else {
                vec![Vec3::Y; positions.len()]
            },
            positions,
            indices: m.indices,
        };
        let geometry_error = |source| ObjError::Geometry { path: path.into(), object: model.name.clone(), source };
        mesh.validate().map_err(geometry_error)?;
        if !has_normals {
            mesh.compute_smooth_normals();
        }
        if mesh.triangle_count() > 0 {
            objects.push(SceneObject {
                name: model.name,
                mesh,
                role: Role::CasterAndReceiver,
                albedo: Vec3::splat(0.7),
            });
        }
    }
    let scene = Scene { objects };
    if scene.triangle_count() == 0 {
        return Err(ObjError::NoTriangles { path: path.into() });
    }
    Ok(scene)
}

/// Triangles the OBJ text's faces make once fan-triangulated (a cheap
/// scan, so that huge files are refused before they are parsed).
pub(crate) fn count_triangles(text: &str) -> usize {
    face_arities(text).map(|n| n.saturating_sub(2)).sum()
}

/// Vertex counts of the `f` elements.
fn face_arities(text: &str) -> impl Iterator<Item = usize> + '_ {
    text.lines().filter_map(|line| {
        let mut words = line.split_whitespace();
        (words.next() == Some("f")).then(|| words.count())
    })
}

/// Parses OBJ text into raw objects for [`super::load_scene_file`]:
/// polygons fan-triangulated, point and line elements ignored (both
/// reported as repairs), normals only where every vertex has one.
pub(crate) fn read_obj(text: &str, path: &Path) -> Result<RawScene, ObjError> {
    let (mut polygons, mut non_triangles) = (0, 0);
    for n in face_arities(text) {
        polygons += usize::from(n > 3);
        non_triangles += usize::from(n < 3);
    }
    non_triangles += text.lines().filter(|l| matches!(l.split_whitespace().next(), Some("l" | "p"))).count();
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let (models, _materials) =
        tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|source| ObjError::Parse { path: path.into(), source })?;
    let objects = models
        .into_iter()
        .map(|model| {
            let m = model.mesh;
            let normals = (m.normals.len() == m.positions.len())
                .then(|| m.normals.chunks_exact(3).map(|n| DVec3::from_slice(n).as_vec3()).collect());
            RawObject {
                name: model.name,
                normals,
                positions: m.positions.chunks_exact(3).map(DVec3::from_slice).collect(),
                indices: m.indices,
            }
        })
        .collect();
    let mut repairs = Vec::new();
    if polygons > 0 {
        repairs.push(Repair::Triangulated { polygons });
    }
    if non_triangles > 0 {
        repairs.push(Repair::IgnoredNonTriangles { count: non_triangles });
    }
    Ok(RawScene { objects, repairs })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scene, ObjError> {
        load_obj_reader(&mut text.as_bytes(), "test.obj")
    }

    #[test]
    fn loads_a_quad_and_computes_normals() {
        let scene = parse("o quad\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nf 1 2 3 4\n").unwrap();
        assert_eq!(scene.triangle_count(), 2);
        let mesh = &scene.objects[0].mesh;
        assert!(mesh.normals.iter().all(|n| (*n - Vec3::Y).length() < 1e-6), "{:?}", mesh.normals);
    }

    #[test]
    fn reports_missing_and_garbled_files() {
        let missing = load_obj("/nonexistent/lixel.obj").unwrap_err();
        assert!(matches!(missing, ObjError::Io { .. }), "{missing}");
        assert!(missing.to_string().contains("/nonexistent/lixel.obj"));

        let garbled = parse("v 0 zero 0\nf 1 2 3\n").unwrap_err();
        assert!(matches!(garbled, ObjError::Parse { .. }), "{garbled}");

        let out_of_range = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n");
        assert!(out_of_range.is_err());

        let empty = parse("# nothing\n").unwrap_err();
        assert!(matches!(empty, ObjError::NoTriangles { .. }), "{empty}");
    }
}
