//! Tessellated primitives centred at the origin, `y` up, counter-clockwise
//! outward-facing triangles. Each takes a triangle budget and picks its
//! tessellation from it, so scenes can be scaled to any size.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use super::Mesh;

/// Adds the quad `a b c d` (counter-clockwise seen from outside) as two triangles.
fn quad(indices: &mut Vec<u32>, a: u32, b: u32, c: u32, d: u32) {
    indices.extend_from_slice(&[a, b, c, a, c, d]);
}

/// A grid of `(nu + 1) x (nv + 1)` vertices from `f(u, v) -> (position,
/// normal)` with `u, v` in `[0, 1]`, triangulated counter-clockwise when
/// `du x dv` points along the normal. `wrap_u` closes the seam by reusing
/// the first column's positions (same vertices, so no cracks).
fn grid(nu: u32, nv: u32, f: impl Fn(f32, f32) -> (Vec3, Vec3)) -> Mesh {
    let mut mesh = Mesh::default();
    for j in 0..=nv {
        for i in 0..=nu {
            let (p, n) = f(i as f32 / nu as f32, j as f32 / nv as f32);
            mesh.positions.push(p);
            mesh.normals.push(n);
        }
    }
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let a = j * row + i;
            quad(&mut mesh.indices, a, a + 1, a + 1 + row, a + row);
        }
    }
    mesh
}

/// Largest `n >= min` with `cost(n) <= budget` (at least `min`).
fn fit(budget: usize, min: u32, cost: impl Fn(u32) -> usize) -> u32 {
    let mut n = min;
    while cost(n + 1) <= budget && n < 1 << 15 {
        n += 1;
    }
    n
}

/// A square floor in the `y = 0` plane, `size` wide, normal `+y`, split into
/// `n x n` quads (`2 n²` triangles, `n` from the budget).
#[must_use]
pub fn floor(size: f32, triangle_budget: usize) -> Mesh {
    let n = fit(triangle_budget, 1, |n| 2 * (n as usize).pow(2));
    let half = 0.5 * size;
    // u runs along +x, v along -z: u x v = +y, so the quads face up.
    grid(n, n, |u, v| (Vec3::new(-half + size * u, 0.0, half - size * v), Vec3::Y))
}

/// A UV sphere of `radius` (about `budget` triangles; poles are fans).
#[must_use]
pub fn sphere(radius: f32, triangle_budget: usize) -> Mesh {
    // s segments around, s / 2 rings: 2 s (s/2 - 1) + 2 s = s² triangles.
    let segments = fit(triangle_budget, 6, |s| (s as usize).pow(2)) & !1;
    let rings = segments / 2;
    let mut mesh = Mesh::default();
    // Vertex rows from the north pole (ring 0) to the south pole; the pole
    // rows repeat their point so that the grid indexing stays uniform.
    for j in 0..=rings {
        let theta = PI * j as f32 / rings as f32;
        for i in 0..=segments {
            let phi = TAU * i as f32 / segments as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
            mesh.positions.push(radius * n);
            mesh.normals.push(n);
        }
    }
    let row = segments + 1;
    for j in 0..rings {
        for i in 0..segments {
            let a = j * row + i;
            let (b, c, d) = (a + 1, a + 1 + row, a + row);
            // Skip the degenerate half of the quads touching a pole.
            if j != 0 {
                mesh.indices.extend_from_slice(&[a, d, b]);
            }
            if j != rings - 1 {
                mesh.indices.extend_from_slice(&[b, d, c]);
            }
        }
    }
    mesh
}

/// An axis-aligned box with the given half extents, each face split into
/// `n x n` quads (`12 n²` triangles).
#[must_use]
pub fn cuboid(half_extents: Vec3, triangle_budget: usize) -> Mesh {
    let n = fit(triangle_budget, 1, |n| 12 * (n as usize).pow(2));
    let mut mesh = Mesh::default();
    // For each face: outward normal and two in-plane axes with u x v = normal.
    let faces = [
        (Vec3::X, Vec3::NEG_Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
    ];
    for (normal, u_axis, v_axis) in faces {
        let face = grid(n, n, |u, v| {
            let p = normal + u_axis * (2.0 * u - 1.0) + v_axis * (2.0 * v - 1.0);
            (p * half_extents, normal)
        });
        mesh.append(&face);
    }
    mesh
}

/// A torus around the `y` axis: ring radius `major`, tube radius `minor`.
#[must_use]
pub fn torus(major: f32, minor: f32, triangle_budget: usize) -> Mesh {
    // 2 s t triangles with s = 2 t segments around the ring.
    let t = fit(triangle_budget, 4, |t| 4 * (t as usize).pow(2));
    grid(2 * t, t, |u, v| {
        let (phi, psi) = (TAU * u, TAU * v);
        let ring = Vec3::new(phi.cos(), 0.0, -phi.sin());
        let n = ring * psi.cos() + Vec3::Y * psi.sin();
        (ring * major + n * minor, n)
    })
}

/// A closed cylinder around the `y` axis from `y = -half_height` to
/// `+half_height`.
#[must_use]
pub fn cylinder(radius: f32, half_height: f32, triangle_budget: usize) -> Mesh {
    // s segments, s / 4 height bands: 2 s (s/4) side + 2 (s - 2) cap triangles.
    let cost = |s: u32| 2 * (s as usize) * (s as usize / 4).max(1) + 2 * (s as usize - 2);
    let s = fit(triangle_budget, 6, cost);
    let bands = (s / 4).max(1);
    let mut mesh = grid(s, bands, |u, v| {
        let phi = TAU * u;
        let n = Vec3::new(phi.cos(), 0.0, -phi.sin());
        (n * radius + Vec3::Y * (half_height * (2.0 * v - 1.0)), n)
    });
    for (y, normal) in [(half_height, Vec3::Y), (-half_height, Vec3::NEG_Y)] {
        let mut cap = Mesh::default();
        for i in 0..s {
            let phi = TAU * i as f32 / s as f32;
            let d = Vec2::from_angle(phi);
            cap.positions.push(Vec3::new(radius * d.x, y, -radius * d.y));
            cap.normals.push(normal);
        }
        // Fan from vertex 0; counter-clockwise seen from above for the top cap.
        for i in 1..s - 1 {
            if normal.y > 0.0 {
                cap.indices.extend_from_slice(&[0, i, i + 1]);
            } else {
                cap.indices.extend_from_slice(&[0, i + 1, i]);
            }
        }
        mesh.append(&cap);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle's winding agrees with its vertex normals (outward, CCW).
    fn assert_outward(mesh: &Mesh) {
        mesh.validate().unwrap();
        for tri in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| mesh.positions[i as usize]);
            let face = (b - a).cross(c - a);
            if face.length() < 1e-9 {
                continue;
            }
            let n: Vec3 = tri.iter().map(|&i| mesh.normals[i as usize]).sum();
            assert!(face.dot(n) > 0.0, "triangle {tri:?} winds against its normals");
        }
    }

    #[test]
    fn primitives_wind_outward_and_respect_budgets() {
        for (mesh, budget) in [
            (floor(10.0, 200), 200),
            (sphere(1.0, 500), 500),
            (cuboid(Vec3::new(1.0, 2.0, 0.5), 300), 300),
            (torus(2.0, 0.5, 800), 800),
            (cylinder(1.0, 2.0, 400), 400),
        ] {
            assert_outward(&mesh);
            assert!(mesh.triangle_count() <= budget, "{} > {budget}", mesh.triangle_count());
            assert!(mesh.triangle_count() * 2 >= budget, "{} far below {budget}", mesh.triangle_count());
        }
    }
}
