//! A side view of a run as a plain SVG drawing: obstacles in grey, body
//! trajectories in blue, tunnelling events as red circles, missed contacts
//! and deep ends as orange crosses.
//!
//! The view projects world space onto two axes chosen by the scene
//! ([`Scene::view`](super::Scene::view)), e.g. x right and y up.

use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::shape::{Shape, TypedShape};
use rapier3d::prelude::{PhysicsWorld, RigidBodyHandle};
use std::fmt::Write;

/// At most this many bodies get a trajectory (the first ones inserted).
const MAX_PATHS: usize = 80;
/// At most this many triangles of a mesh are drawn.
const MAX_TRIANGLES: usize = 4000;
/// Drawing size in pixels (the longer side).
const SIZE: Real = 900.0;
/// Obstacle segments longer than this (metres) do not set the frame.
const MAX_FRAMED_SEGMENT: Real = 0.5 * PLANE_SPAN;
/// Half-spaces are drawn as a segment this long (metres) around their point.
const PLANE_SPAN: Real = 50.0;

/// What a run leaves to draw.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// World axes of the view: horizontal, vertical.
    pub view: [usize; 2],
    /// Obstacle outlines as 3D segments (fixed colliders, at the start).
    pub segments: Vec<(Vector, Vector)>,
    /// Trajectories: centres of mass, one per step, per traced body.
    pub paths: Vec<(RigidBodyHandle, Vec<Vector>)>,
    /// Tunnelling events (world points).
    pub tunnels: Vec<Vector>,
    /// Missed contacts and deep ends (world points).
    pub contacts: Vec<Vector>,
}

impl Trace {
    /// Starts a trace of `world`: outlines of the fixed colliders and the
    /// initial centres of mass of the moving bodies.
    pub fn start(world: &PhysicsWorld, view: [usize; 2]) -> Self {
        let mut segments = Vec::new();
        for (_, collider) in world.colliders.iter() {
            let fixed = collider
                .parent()
                .and_then(|h| world.bodies.get(h))
                .is_none_or(|b| b.is_fixed());
            if fixed {
                outline(collider.shape(), collider.position(), &mut segments);
            }
        }
        let paths = world
            .bodies
            .iter()
            .filter(|(_, b)| !b.is_fixed())
            .take(MAX_PATHS)
            .map(|(h, b)| (h, vec![b.center_of_mass()]))
            .collect();
        Self {
            view: [view[0].min(2), view[1].min(2)],
            segments,
            paths,
            ..Self::default()
        }
    }

    /// Appends the current centres of mass to the trajectories.
    pub fn record(&mut self, world: &PhysicsWorld) {
        for (handle, path) in &mut self.paths {
            if let Some(body) = world.bodies.get(*handle) {
                path.push(body.center_of_mass());
            }
        }
    }

    /// The SVG document, titled `title`.
    pub fn to_svg(&self, title: &str) -> String {
        let [h, v] = [self.view[0].min(2), self.view[1].min(2)];
        let project = |p: Vector| (p[h], p[v]);
        // Frame the trajectories, the events and the obstacles of a sane
        // size (a half-space's long cross would squash everything else).
        let finite_segments = self
            .segments
            .iter()
            .filter(|(a, b)| (*a - *b).length() < MAX_FRAMED_SEGMENT)
            .flat_map(|(a, b)| [project(*a), project(*b)]);
        let mut points: Vec<(Real, Real)> = self
            .paths
            .iter()
            .flat_map(|(_, path)| path.iter().copied().map(project))
            .chain(self.tunnels.iter().copied().map(project))
            .chain(finite_segments)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        if points.is_empty() {
            points = self
                .segments
                .iter()
                .flat_map(|(a, b)| [project(*a), project(*b)])
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .collect();
        }
        let (mut x0, mut x1, mut y0, mut y1) = bounds(&points);
        // Some margin, and never a zero-size frame.
        let pad = 0.1 * (x1 - x0).max(y1 - y0).max(1.0);
        x0 -= pad;
        x1 += pad;
        y0 -= pad;
        y1 += pad;
        let scale = SIZE / (x1 - x0).max(y1 - y0);
        let (width, height) = ((x1 - x0) * scale, (y1 - y0) * scale);
        // SVG's y grows downwards.
        let to_px = |p: Vector| {
            let (x, y) = project(p);
            ((x - x0) * scale, (y1 - y) * scale)
        };
        let mut svg = String::new();
        let _ = writeln!(
            svg,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.1} {height:.1}">"#
        );
        let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            svg,
            r#"<text x="8" y="18" font-family="monospace" font-size="14">{}</text>"#,
            escape(title)
        );
        let _ = writeln!(svg, r##"<g stroke="#888" stroke-width="1" fill="none">"##);
        for (a, b) in &self.segments {
            let ((ax, ay), (bx, by)) = (to_px(*a), to_px(*b));
            if [ax, ay, bx, by].iter().all(|c| c.is_finite()) {
                let _ = writeln!(
                    svg,
                    r#"<line x1="{ax:.1}" y1="{ay:.1}" x2="{bx:.1}" y2="{by:.1}"/>"#
                );
            }
        }
        let _ = writeln!(svg, "</g>");
        let _ = writeln!(
            svg,
            r##"<g stroke="#2a6fdb" stroke-width="1" fill="none" opacity="0.7">"##
        );
        for (_, path) in &self.paths {
            let mut d = String::new();
            for p in path {
                let (x, y) = to_px(*p);
                if x.is_finite() && y.is_finite() {
                    let _ = write!(d, "{x:.1},{y:.1} ");
                }
            }
            let _ = writeln!(svg, r#"<polyline points="{}"/>"#, d.trim_end());
        }
        let _ = writeln!(svg, "</g>");
        let _ = writeln!(svg, r##"<g stroke="#f08c00" stroke-width="1.5">"##);
        for p in &self.contacts {
            let (x, y) = to_px(*p);
            if x.is_finite() && y.is_finite() {
                let _ = writeln!(
                    svg,
                    r#"<path d="M{:.1},{:.1} l8,8 m0,-8 l-8,8"/>"#,
                    x - 4.0,
                    y - 4.0
                );
            }
        }
        let _ = writeln!(svg, "</g>");
        let _ = writeln!(
            svg,
            r##"<g stroke="#e03131" stroke-width="2" fill="none">"##
        );
        for p in &self.tunnels {
            let (x, y) = to_px(*p);
            if x.is_finite() && y.is_finite() {
                let _ = writeln!(svg, r#"<circle cx="{x:.1}" cy="{y:.1}" r="6"/>"#);
            }
        }
        let _ = writeln!(svg, "</g>\n</svg>");
        svg
    }
}

/// Smallest box around `points`; the unit box around 0 when empty.
fn bounds(points: &[(Real, Real)]) -> (Real, Real, Real, Real) {
    if points.is_empty() {
        return (-1.0, 1.0, -1.0, 1.0);
    }
    points.iter().fold(
        (Real::MAX, Real::MIN, Real::MAX, Real::MIN),
        |(x0, x1, y0, y1), &(x, y)| (x0.min(x), x1.max(x), y0.min(y), y1.max(y)),
    )
}

/// Line segments outlining `shape` at `pose`: box edges, mesh edges, a
/// cross for a half-space's plane, the bounding box for anything else.
fn outline(shape: &dyn Shape, pose: &Pose, out: &mut Vec<(Vector, Vector)>) {
    match shape.as_typed_shape() {
        TypedShape::Cuboid(c) => box_edges(pose, -c.half_extents, c.half_extents, out),
        TypedShape::TriMesh(mesh) => {
            for tri in mesh.triangles().take(MAX_TRIANGLES) {
                let (a, b, c) = (
                    pose.transform_point(tri.a),
                    pose.transform_point(tri.b),
                    pose.transform_point(tri.c),
                );
                out.extend([(a, b), (b, c), (c, a)]);
            }
        }
        TypedShape::HalfSpace(plane) => {
            let n = pose.rotation * plane.normal;
            let (u, w) = n.any_orthonormal_pair();
            let o = pose.translation;
            out.push((o - u * PLANE_SPAN, o + u * PLANE_SPAN));
            out.push((o - w * PLANE_SPAN, o + w * PLANE_SPAN));
        }
        TypedShape::Compound(compound) => {
            for (child_pose, child) in compound.shapes() {
                outline(child.as_ref(), &(*pose * *child_pose), out);
            }
        }
        _ => {
            let aabb = shape.compute_aabb(pose);
            box_edges(&Pose::IDENTITY, aabb.mins, aabb.maxs, out);
        }
    }
}

/// The 12 edges of the box [lo, hi] placed at `pose`.
fn box_edges(pose: &Pose, lo: Vector, hi: Vector, out: &mut Vec<(Vector, Vector)>) {
    let corner = |k: usize| {
        pose.transform_point(Vector::new(
            if k & 1 != 0 { hi.x } else { lo.x },
            if k & 2 != 0 { hi.y } else { lo.y },
            if k & 4 != 0 { hi.z } else { lo.z },
        ))
    };
    for k in 0..8 {
        for bit in [1, 2, 4] {
            if k & bit == 0 {
                out.push((corner(k), corner(k | bit)));
            }
        }
    }
}

/// Escapes text for an SVG text node.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
