//! Building blocks shared by the scene builders: walls, floors, terrain,
//! fans. Each returns the handles a builder needs for its guards.

use super::guard::{Face, Guard};
use rapier3d::math::{Pose, Real, Rotation, Vector};
use rapier3d::parry::shape::SharedShape;
use rapier3d::prelude::{
    ColliderBuilder, ColliderHandle, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle,
};

/// A fixed axis-aligned box (a wall, a floor slab), without a body.
pub fn fixed_box(world: &mut PhysicsWorld, center: Vector, half: Vector) -> ColliderHandle {
    world.insert_collider(
        ColliderBuilder::cuboid(half.x, half.y, half.z).translation(center),
        None,
    )
}

/// A fixed thin wall and the guard face on its far side: `axis` is the world
/// axis the wall is thin along, `sign` the direction the bodies come from
/// *towards* (so the forbidden side is `sign` along `axis`).
pub fn thin_wall(
    world: &mut PhysicsWorld,
    center: Vector,
    half: Vector,
    axis: usize,
    sign: Real,
) -> (ColliderHandle, Face) {
    let handle = fixed_box(world, center, half);
    (handle, Face::of_box(center, half, axis, sign))
}

/// Vertices and triangles of a grid over x ∈ [x0, x0 + size], z ∈ [z0, z0 +
/// size] with `n` cells a side and height `height(x, z)`.
pub fn grid_mesh(
    x0: Real,
    z0: Real,
    size: Real,
    n: u32,
    height: impl Fn(Real, Real) -> Real,
) -> (Vec<Vector>, Vec<[u32; 3]>) {
    let n = n.max(1);
    let step = size / n as Real;
    let mut vertices = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let (x, z) = (x0 + i as Real * step, z0 + j as Real * step);
            vertices.push(Vector::new(x, height(x, z), z));
        }
    }
    let at = |i: u32, j: u32| i * (n + 1) + j;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..n {
            // Wound so the normals point up (+y).
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            triangles.push([at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
        }
    }
    (vertices, triangles)
}

/// A fixed triangle-mesh surface from [`grid_mesh`]; `None` if parry rejects it.
pub fn fixed_mesh(
    world: &mut PhysicsWorld,
    mesh: (Vec<Vector>, Vec<[u32; 3]>),
) -> Option<ColliderHandle> {
    let builder = ColliderBuilder::trimesh(mesh.0, mesh.1).ok()?;
    Some(world.insert_collider(builder, None))
}

/// The triangles of an axis-aligned box (a closed mesh), centred at `center`.
pub fn box_triangles(center: Vector, half: Vector, out: &mut (Vec<Vector>, Vec<[u32; 3]>)) {
    let base = out.0.len() as u32;
    for k in 0..8u32 {
        let sign = |bit: u32| if k & bit != 0 { 1.0 } else { -1.0 };
        out.0
            .push(center + Vector::new(sign(1) * half.x, sign(2) * half.y, sign(4) * half.z));
    }
    // Faces as corner indices (bit 0 = +x, bit 1 = +y, bit 2 = +z), outward.
    const QUADS: [[u32; 4]; 6] = [
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
    ];
    for q in QUADS {
        out.1.push([base + q[0], base + q[1], base + q[2]]);
        out.1.push([base + q[0], base + q[2], base + q[3]]);
    }
}

/// A dynamic body spinning at `spin` (rad/s, world) with one collider.
pub fn spinner(
    world: &mut PhysicsWorld,
    at: Vector,
    collider: ColliderBuilder,
    spin: Vector,
    fast_rotation: bool,
) -> RigidBodyHandle {
    let body = RigidBodyBuilder::dynamic()
        .translation(at)
        .angvel(spin)
        .ccd_enabled(true)
        .allow_fast_rotation(fast_rotation)
        .gyroscopic_forces_enabled(false);
    world.insert(body, collider).0
}

/// A fan: a hub ball with `blades` thin blades in the xy plane, each
/// `length` long, as one compound shape (spins about z).
pub fn fan_shape(blades: u32, length: Real, width: Real, thickness: Real) -> SharedShape {
    let mut parts = vec![(Pose::IDENTITY, SharedShape::ball(width))];
    for k in 0..blades.max(1) {
        let angle = k as Real * std::f32::consts::TAU / blades.max(1) as Real;
        let rotation = Rotation::from_axis_angle(Vector::Z, angle);
        let center = rotation * Vector::new(0.5 * length, 0.0, 0.0);
        let blade = SharedShape::cuboid(0.5 * length, 0.5 * width, 0.5 * thickness);
        parts.push((Pose::from_parts(center, rotation), blade));
    }
    SharedShape::compound(parts)
}

/// `Crossing` guards for every body against every obstacle.
pub fn crossing_guards(bodies: &[RigidBodyHandle], obstacles: &[ColliderHandle]) -> Vec<Guard> {
    let mut guards = Vec::new();
    for &body in bodies {
        for &obstacle in obstacles {
            guards.push(Guard::Crossing { body, obstacle });
        }
    }
    guards
}

/// `Beyond` guards for every body against one face.
pub fn beyond_guards(bodies: &[RigidBodyHandle], face: Face) -> Vec<Guard> {
    bodies
        .iter()
        .map(|&body| Guard::Beyond { body, face })
        .collect()
}

/// A small deterministic pseudo-random sequence in [0, 1) (no dependency,
/// same scene every run).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn unit(&mut self) -> Real {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as Real) / ((1u64 << 24) as Real)
    }

    /// A value in [lo, hi).
    pub fn range(&mut self, lo: Real, hi: Real) -> Real {
        lo + (hi - lo) * self.unit()
    }
}

/// `Crossing` guards both ways for two bodies meeting each other: neither
/// centre of mass may enter or pass the other body's first collider.
pub fn mutual_guards(world: &PhysicsWorld, a: RigidBodyHandle, b: RigidBodyHandle) -> Vec<Guard> {
    let mut guards = Vec::new();
    for (body, other) in [(a, b), (b, a)] {
        if let Some(&obstacle) = world
            .bodies
            .get(other)
            .and_then(|rb| rb.colliders().first())
        {
            guards.push(Guard::Crossing { body, obstacle });
        }
    }
    guards
}

/// Whether every dynamic body is at rest: linear speed below `speed` (m/s)
/// and angular speed below `spin` (rad/s). Used by the tests of the scenes
/// that claim `Effects::settles`.
pub fn all_at_rest(world: &PhysicsWorld, speed: Real, spin: Real) -> bool {
    world
        .bodies
        .iter()
        .filter(|(_, rb)| rb.is_dynamic())
        .all(|(_, rb)| rb.linvel().length() < speed && rb.angvel().length() < spin)
}

/// A row of resting boxes and a position-based kinematic paddle (a blade
/// 6 cm thick, 1 m tall, 2 m wide) scripted to slide through them along x.
pub struct PaddleRow {
    /// Where the paddle's slide starts and ends (its period is `period`).
    pub from: Vector,
    pub to: Vector,
    /// Seconds for one round trip.
    pub period: Real,
    /// The boxes: how many, the first one's centre, the spacing along x,
    /// the half extent.
    pub boxes: usize,
    pub first: Vector,
    pub spacing: Real,
    pub half: Real,
    /// Whether the boxes have rapier's `ccd_enabled`.
    pub ccd: bool,
}

impl PaddleRow {
    /// Builds the paddle and the boxes; the guards say no box may end
    /// behind the blade.
    pub fn build(&self, world: &mut PhysicsWorld) -> super::Setup {
        use super::script::{Motion, Script};
        let paddle =
            world.insert_body(RigidBodyBuilder::kinematic_position_based().translation(self.from));
        let blade = world.insert_collider(ColliderBuilder::cuboid(0.03, 0.5, 1.0), Some(paddle));
        let boxes: Vec<RigidBodyHandle> = (0..self.boxes)
            .map(|k| {
                let at = self.first + Vector::X * (self.spacing * k as Real);
                let body = RigidBodyBuilder::dynamic()
                    .translation(at)
                    .ccd_enabled(self.ccd);
                let collider =
                    ColliderBuilder::cuboid(self.half, self.half, self.half).friction(0.6);
                world.insert(body, collider).0
            })
            .collect();
        let script = Script {
            body: paddle,
            motion: Motion::Slide {
                from: self.from,
                to: self.to,
                rotation: Rotation::IDENTITY,
                period: self.period,
            },
        };
        super::Setup {
            guards: crossing_guards(&boxes, &[blade]),
            scripts: vec![script],
        }
    }
}
