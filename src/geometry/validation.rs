//! [`ConvexPolyhedron::sanity_check`]: the structural invariants every body
//! keeps, in one place for the unit tests, the property tests and users who
//! build bodies from their own planes.

use std::collections::HashMap;

use super::ConvexPolyhedron;

impl ConvexPolyhedron {
    /// Checks the invariants of a non-empty body and names the first broken
    /// one: every face has at least three distinct vertices and a unit
    /// normal; every directed edge occurs once and its reverse once (closed,
    /// consistently oriented, index-shared); every vertex is used; Euler
    /// characteristic `V - E + F = 2`; every vertex lies within `tol` outside
    /// every face plane, and within `max(tol, 1e-6 · scale)` inside its own
    /// faces' planes (where a plane through a sliver is ill-conditioned, the
    /// hull and extrusion push it out rather than let it cut the body); the
    /// volume is positive up to `tol` times the surface area. An empty body
    /// passes when it has no vertices.
    ///
    /// # Errors
    /// A description of the first invariant that fails.
    pub fn sanity_check(&self, tol: f64) -> Result<(), String> {
        if self.is_empty() {
            return if self.vertices().is_empty() { Ok(()) } else { Err("empty body with vertices".into()) };
        }
        let inner_tol = tol.max(1e-6 * self.scale());
        let vertices = self.vertices();
        let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
        let mut used = vec![false; vertices.len()];
        let mut area = 0.0;
        for (f, face) in self.faces().enumerate() {
            let indices = face.indices();
            if indices.len() < 3 {
                return Err(format!("face {f} has {} vertices", indices.len()));
            }
            for (a, b) in face.edges() {
                if a == b {
                    return Err(format!("repeated vertex in face {f}"));
                }
                if edges.insert((a, b), f).is_some() {
                    return Err(format!("directed edge {a}->{b} twice"));
                }
                used[a] = true;
            }
            for &i in indices {
                let d = face.plane().signed_distance(vertices[i]);
                if !(-inner_tol <= d && d <= tol) {
                    return Err(format!("vertex {i} is {d} off face {f}"));
                }
            }
            if !((face.plane().normal.length() - 1.0).abs() < 1e-12) {
                return Err(format!("face {f} normal not unit"));
            }
            let v0 = vertices[indices[0]];
            area += (2..indices.len())
                .map(|k| 0.5 * (vertices[indices[k - 1]] - v0).cross(vertices[indices[k]] - v0).length())
                .sum::<f64>();
        }
        if let Some(&(a, b)) = edges.keys().find(|&&(a, b)| !edges.contains_key(&(b, a))) {
            return Err(format!("edge {a}->{b} has one face"));
        }
        if let Some(i) = used.iter().position(|&u| !u) {
            return Err(format!("unused vertex {i}"));
        }
        let (v, e, f) = (vertices.len() as i64, edges.len() as i64 / 2, self.faces().len() as i64);
        if v - e + f != 2 {
            return Err(format!("V - E + F = {v} - {e} + {f} != 2"));
        }
        for (f, plane) in self.planes().enumerate() {
            if let Some(i) = vertices.iter().position(|&x| plane.signed_distance(x) > tol) {
                return Err(format!("vertex {i} outside the plane of face {f}"));
            }
        }
        if !(self.volume() > -tol * area) {
            return Err(format!("volume {}", self.volume()));
        }
        Ok(())
    }
}
