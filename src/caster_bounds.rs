//! The depth range of a caster body without building the body.
//!
//! A map's depth row must hold every caster of its receivers: the body
//! `conv(F ∪ l) ∩ C` (positional lights) or `F` extruded towards the light
//! `∩ C` (directional), with `C` the casters' box. Clipping `C` by the
//! towards-light planes builds it exactly, yet the depth row reads only the
//! extremes of a few functions over it. [`CasterBounds`] keeps the box and
//! the planes and answers those extremes directly:
//! - linear functions (the projective `w`, a directional light's `d·x`):
//!   their exact minimum as a small linear program
//!   ([`crate::geometry::maximize_in_box`]); their maximum either by a second
//!   program or, where the caller knows it, as the largest value over the
//!   focus vertices and the light (the body lies in their hull, where a
//!   linear function peaks at one of them; a directional light's function
//!   must not grow towards the light for that);
//! - a positional light's distance `|x - l|`: its maximum over the body is
//!   at most the farthest focus vertex (the body lies in `conv(F ∪ l)`, and
//!   a convex function peaks at a vertex, `l` itself being at distance 0);
//!   its minimum is bounded from below by the largest of `0`, the distance
//!   from `l` to the box and `min u·(x - l)` over the body for two unit
//!   directions `u` (each a linear program; `|x - l| >= u·(x - l)`), so the
//!   range may be wider than the body's, never narrower.
//!
//! Every extreme is widened by [`WIDEN`] plane tolerances (times the
//! function's gradient length): the clipped body puts its vertices within a
//! tolerance of its planes, and where two planes meet at a small angle a
//! corner moves by the tolerance over the angle's sine; the linear programs
//! allow the same tolerance. The range so holds every vertex of the body
//! [`crate::ShadowProblem::caster_body`] builds (tested against it) and is
//! within a few tolerances of its vertex range for the linear functions.

use std::sync::{Mutex, PoisonError};

use glam::{DVec3, DVec4};

use crate::geometry::{maximize_in_box, padded_box, Plane};

/// How many plane tolerances every extreme is widened by.
const WIDEN: f64 = 64.0;

/// How many plane tolerances the half-spaces are grown by for the linear
/// programs: the clip keeps vertices within one tolerance outside a plane,
/// which a plane at a grazing angle turns into a long way along it.
const GROW: f64 = 2.0;

/// The growth of a second try when the first finds no body.
const RETRY_GROW: f64 = 1e3;

/// How many linear programs' answers the bounds remember: a solve asks at
/// most three (the depth function's two extremes and the distance's second
/// direction).
const REMEMBERED: usize = 4;

/// A linear program's objective (as bits) and its answer.
type Answer = Option<([u64; 3], Option<DVec3>)>;

/// The caster body of one focus body, kept as the half-spaces that bound it.
#[derive(Debug, Default)]
pub(crate) struct CasterBounds {
    /// The casters' box, padded as [`crate::geometry::ConvexPolyhedron::from_aabb`]
    /// pads it; `None` when there are no casters (empty focus, invalid box or
    /// planes).
    region: Option<(DVec3, DVec3)>,
    /// The focus body's towards-light planes (already grown).
    pub(crate) planes: Vec<Plane>,
    /// The largest distance of a focus vertex from a positional light.
    focus_far: f64,
    /// The problem's plane tolerance.
    eps: f64,
    /// Whether a focus vertex or the light lies in the box (then the body
    /// is not empty, whatever rounding makes of the linear programs).
    known_nonempty: bool,
    /// The last answers of [`argmax`](Self::argmax), most recent first.
    /// They depend only on the fields above, so they travel with the bounds
    /// (a workspace's per-light cache keeps them): a still light and camera
    /// ask the same objectives again and get them without solving. (A
    /// mutex, not a cell: [`crate::Samples`] holds bounds and is shared
    /// between threads; it is never contended.)
    answers: Mutex<[Answer; REMEMBERED]>,
}

impl CasterBounds {
    /// No casters, with `planes` as the plane buffer (cleared).
    pub(crate) fn new(mut planes: Vec<Plane>) -> Self {
        planes.clear();
        Self { region: None, planes, focus_far: 0.0, eps: 0.0, known_nonempty: false, answers: Mutex::default() }
    }

    /// The plane buffer, for reuse.
    pub(crate) fn into_planes(self) -> Vec<Plane> {
        self.planes
    }

    /// Makes these bounds equal to `other`, reusing the plane buffer.
    pub(crate) fn copy_from(&mut self, other: &Self) {
        self.planes.clear();
        self.planes.extend_from_slice(&other.planes);
        self.region = other.region;
        self.focus_far = other.focus_far;
        self.eps = other.eps;
        self.known_nonempty = other.known_nonempty;
        *self.answers_mut() = other.answers();
    }

    /// No casters (an empty focus body).
    pub(crate) fn clear(&mut self) {
        self.region = None;
        self.planes.clear();
        *self.answers_mut() = [None; REMEMBERED];
    }

    /// The box `[min, max]` cut by [`planes`](Self::planes) (filled by the
    /// caller) for a focus body with vertices `focus`, lit from `light` (a
    /// positional light's position), with `eps` the plane tolerance. A box
    /// that is inverted or not finite, or a plane that is not finite, leaves
    /// no casters, as clipping by them would.
    pub(crate) fn set(&mut self, min: DVec3, max: DVec3, focus: &[DVec3], light: Option<DVec3>, eps: f64) {
        *self.answers_mut() = [None; REMEMBERED];
        let finite = self.planes.iter().all(Plane::is_finite);
        self.region = padded_box(min, max).filter(|_| finite);
        self.focus_far = light.map_or(0.0, |l| focus.iter().map(|v| v.distance(l)).fold(0.0, f64::max));
        self.eps = eps;
        let Some((min, max)) = self.region else {
            return;
        };
        // A plane whose half-space holds the whole box cannot bind:
        // dropped (the faces a focus body shares with the box).
        let (center, half) = (0.5 * (min + max), 0.5 * (max - min));
        self.planes.retain(|p| p.signed_distance(center) + p.normal.abs().dot(half) > 0.0);
        // The body holds `(focus ∪ l) ∩ C`.
        let grown = DVec3::splat(GROW * eps);
        let in_box = |p: &DVec3| p.cmpge(min - grown).all() && p.cmple(max + grown).all();
        self.known_nonempty = focus.iter().chain(light.as_ref()).any(in_box);
    }

    /// The widening of an extreme of a function with gradient `c`.
    fn widening(&self, c: DVec3) -> f64 {
        WIDEN * self.eps * c.length()
    }

    /// A point of the body maximizing `c·x`; `None` when the body is empty.
    ///
    /// Near-parallel planes (a light grazing a flat focus) can make the
    /// body a sliver that rounding calls empty: an empty answer is checked
    /// once more with the planes grown by [`RETRY_GROW`] tolerances, and a
    /// body known not to be empty then falls back to the box's corner (a
    /// bound over the whole box), as does a point that is not finite.
    ///
    /// An objective asked before (bit-equal, among the last
    /// [`REMEMBERED`]) gets the same answer without solving again.
    fn argmax(&self, c: DVec3) -> Option<DVec3> {
        let key = c.to_array().map(f64::to_bits);
        if let Some(&(_, x)) = self.answers().iter().flatten().find(|(k, _)| *k == key) {
            return x;
        }
        let x = self.solve(c);
        let mut answers = self.answers.lock().unwrap_or_else(PoisonError::into_inner);
        answers.rotate_right(1);
        answers[0] = Some((key, x));
        x
    }

    /// The remembered answers.
    fn answers(&self) -> [Answer; REMEMBERED] {
        *self.answers.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The remembered answers, to replace.
    fn answers_mut(&mut self) -> &mut [Answer; REMEMBERED] {
        self.answers.get_mut().unwrap_or_else(PoisonError::into_inner)
    }

    /// [`argmax`](Self::argmax) without the remembered answers.
    fn solve(&self, c: DVec3) -> Option<DVec3> {
        let (min, max) = self.region?;
        let corner = DVec3::select(c.cmpge(DVec3::ZERO), max, min);
        let solve = |grow: f64| maximize_in_box(min, max, &self.planes, grow * self.eps, c, self.eps);
        match solve(GROW).or_else(|| solve(RETRY_GROW)) {
            Some(x) if x.is_finite() => Some(x),
            Some(_) => Some(corner),
            None => self.known_nonempty.then_some(corner),
        }
    }

    /// `(min, max)` of `h·[x, 1]` over the body, widened, and a point of
    /// the body where the minimum is reached; `None` when there are no
    /// casters.
    ///
    /// `hull_max`, when the caller has it, is the function's largest value
    /// over the focus vertices and the light (a positional light), or over
    /// the focus vertices alone (a directional light whose function does not
    /// grow towards the light): the body lies in their hull (`conv(F ∪ l)`,
    /// or `F` extruded towards the light), where a linear function peaks at
    /// one of them. The maximum is then that value, or the box's corner where
    /// that is lower, widened, and only the minimum is solved for.
    pub(crate) fn linear_range(&self, h: DVec4, hull_max: Option<f64>) -> Option<(f64, f64, DVec3)> {
        let c = h.truncate();
        let widen = self.widening(c);
        let hi = match hull_max {
            Some(top) => {
                let (min, max) = self.region?;
                let corner = DVec3::select(c.cmpge(DVec3::ZERO), max, min);
                (c.dot(corner) + h.w).min(top) + widen
            }
            None => c.dot(self.argmax(c)?) + h.w + widen,
        };
        let lo = self.argmax(-c)?;
        Some((c.dot(lo) + h.w - widen, hi, lo))
    }

    /// `(min, max)` bounds of `|x - light|` over the body, widened, from
    /// `nearest`, the body's point where `toward·x` is least (as
    /// [`linear_range`](Self::linear_range) finds it for a direction from
    /// the light into the body). `None` when there are no casters.
    pub(crate) fn distance_range(&self, light: DVec3, toward: DVec3, nearest: DVec3) -> Option<(f64, f64)> {
        let (min, max) = self.region?;
        let mut lower = (light.clamp(min, max) - light).length().max(toward.normalize_or_zero().dot(nearest - light));
        // A second direction, at the first one's nearest point: exact when
        // that is the body's point nearest the light.
        let u = (nearest - light).normalize_or_zero();
        if u != DVec3::ZERO {
            lower = lower.max(u.dot(self.argmax(-u)? - light));
        }
        let widen = self.widening(DVec3::X);
        Some((lower - widen, self.focus_far + widen))
    }
}

impl Clone for CasterBounds {
    fn clone(&self) -> Self {
        Self {
            region: self.region,
            planes: self.planes.clone(),
            focus_far: self.focus_far,
            eps: self.eps,
            known_nonempty: self.known_nonempty,
            answers: Mutex::new(self.answers()),
        }
    }
}

impl crate::workspace::CopyFrom for CasterBounds {
    fn copy_from(&mut self, other: &Self) {
        CasterBounds::copy_from(self, other);
    }
}
