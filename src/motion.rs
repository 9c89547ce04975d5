//! The motion of a rigid frame over one step, as enclosures in time.
//!
//! A shape's frame moves with its body: the body's centre of mass `c`
//! follows a polynomial path and the body turns about it at a constant
//! angular velocity. With `τ ∈ [0, 1]` the fraction of the step:
//!
//! ```text
//! c(τ) = c0 + d·τ + b·τ²              d = v·dt, b = ½·a·dt²
//! R(τ) = exp(τ·[θ]×)·R0               θ = ω·dt, the step's rotation vector
//! p(τ) = c(τ) + exp(τ·[θ]×)·(p0 − c0) the frame's origin
//! ```
//!
//! `exp(τ[θ]×)` is Rodrigues' formula `I + sin φ·K + (1 − cos φ)·K²` with
//! `φ = |θ|·τ` and `K = [θ/|θ|]×`; `sin`/`cos` come from the arithmetic's own
//! rigorous series, valid for any angle (several turns a step is only
//! slower: the bisection narrows the nodes until the series is tight).
//!
//! A motion's fields *define* the true motion: velocities are turned into
//! per-step displacements once, in `f64`, and every enclosure contains the
//! motion so defined. [`Motion::pose_at`] evaluates the same definition in
//! plain `f64` for ground truth and for the pose reported at an impact.

use crate::enclosure::rounding::{bound, up};
use crate::enclosure::{Enclosure, Interval, TimeSpan};
use crate::error::{CcdError, check_finite};
use nalgebra::{Isometry3, Matrix3, Point3, Translation3, UnitQuaternion, Vector3};
use smallvec::SmallVec;
use std::f64::consts::{FRAC_PI_2, TAU};

/// A rigid pose with enclosed entries: `x ↦ rotation·x + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose<E: Enclosure> {
    pub rotation: Matrix3<E>,
    pub translation: Vector3<E>,
}

impl<E: Enclosure> Pose<E> {
    /// A pose known exactly.
    pub fn constant(rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Pose<E> {
        Pose {
            rotation: rotation.map(E::constant),
            translation: translation.map(E::constant),
        }
    }

    /// `rotation·v` for a fixed vector of the frame.
    pub fn rotate(&self, v: &Vector3<f64>) -> Vector3<E> {
        Vector3::from_fn(|i, _| E::dot_f64(row(&self.rotation, i), [v.x, v.y, v.z]))
    }

    /// The world position of a fixed point of the frame.
    pub fn transform_point(&self, p: &Vector3<f64>) -> Vector3<E> {
        self.rotate(p) + self.translation
    }

    /// `rotationᵀ·v`: a world vector in the frame's axes.
    pub fn inverse_rotate(&self, v: &Vector3<E>) -> Vector3<E> {
        let v = [v.x, v.y, v.z];
        // A frame that does not turn (a fixed target) holds plain numbers:
        // products by them cost a third of two enclosures'.
        if let Some(own) = self.exact_rotation() {
            return Vector3::from_fn(|i, _| E::dot_f64(v, column(&own, i)));
        }
        // Written out: nalgebra's generic product multiplies by α = 1 and
        // β = 0 in the enclosure arithmetic, three times the work.
        Vector3::from_fn(|i, _| E::dot(column(&self.rotation, i), v))
    }

    /// The rotation as plain numbers, when every entry is exact (a frame
    /// that does not turn).
    fn exact_rotation(&self) -> Option<Matrix3<f64>> {
        let mut m = Matrix3::zeros();
        for (out, e) in m.iter_mut().zip(self.rotation.iter()) {
            *out = e.exact_value()?;
        }
        Some(m)
    }

    /// The pose of `other` seen from this frame: `self⁻¹·other`. Where one
    /// of the two does not turn, its exact rotation enters the products as
    /// plain numbers, half their cost.
    pub fn relative(&self, other: &Pose<E>) -> Pose<E> {
        let d = other.translation - self.translation;
        let d = [d.x, d.y, d.z];
        match (self.exact_rotation(), other.exact_rotation()) {
            (Some(own), _) => Pose {
                rotation: Matrix3::from_fn(|i, j| {
                    E::dot_f64(column(&other.rotation, j), column(&own, i))
                }),
                translation: Vector3::from_fn(|i, _| E::dot_f64(d, column(&own, i))),
            },
            (None, Some(theirs)) => Pose {
                rotation: Matrix3::from_fn(|i, j| {
                    E::dot_f64(column(&self.rotation, i), column(&theirs, j))
                }),
                translation: Vector3::from_fn(|i, _| E::dot(column(&self.rotation, i), d)),
            },
            (None, None) => Pose {
                rotation: Matrix3::from_fn(|i, j| {
                    E::dot(column(&self.rotation, i), column(&other.rotation, j))
                }),
                translation: Vector3::from_fn(|i, _| E::dot(column(&self.rotation, i), d)),
            },
        }
    }
}

/// Row `i` of a matrix, for [`Enclosure::dot`].
pub(crate) fn row<T: Copy>(m: &Matrix3<T>, i: usize) -> [T; 3] {
    [m[(i, 0)], m[(i, 1)], m[(i, 2)]]
}

/// Column `j` of a matrix, for [`Enclosure::dot`].
pub(crate) fn column<T: Copy>(m: &Matrix3<T>, j: usize) -> [T; 3] {
    [m[(0, j)], m[(1, j)], m[(2, j)]]
}

/// Any motion a user can write as enclosures: the write-up asks for
/// arbitrary trajectories, not only constant velocities.
pub trait Trajectory {
    /// The frame's pose for every `τ` of `span`, enclosed.
    fn pose<E: Enclosure>(&self, span: TimeSpan) -> Pose<E>;

    /// The pose at one `τ`, in plain `f64` (ground truth, reported poses).
    fn pose_at(&self, tau: f64) -> Isometry3<f64>;

    /// Only the frame's origin over `span`: all a shape whose distance
    /// ignores its orientation (a ball) needs, and cheaper than [`pose`].
    ///
    /// [`pose`]: Trajectory::pose
    fn origin<E: Enclosure>(&self, span: TimeSpan) -> Vector3<E> {
        self.pose(span).translation
    }
}

/// The constant-rotation part of a motion, prepared once.
///
/// With `K = [k]×` for the unit axis `k` and `K² = k·kᵀ − I`, Rodrigues'
/// formula gives the frame's rotation and the turned arm from the centre as
/// `R(τ) = R0 + sin φ·(K·R0) + (1 − cos φ)·(K²·R0)` and
/// `arm(τ) = arm + sin φ·(K·arm) + (1 − cos φ)·(K²·arm)`, `φ = |θ|·τ`. The
/// products are computed once and kept as `f64` values plus one error
/// radius per group, so that each node costs two multiplications of an
/// enclosure by a number per entry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Spin {
    angle: f64,
    angle_err: f64,
    rot_k: Matrix3<f64>,
    rot_k2: Matrix3<f64>,
    rot_err: f64,
    arm_k: Vector3<f64>,
    arm_k2: Vector3<f64>,
    arm_err: f64,
}

/// The radius of an interval about its midpoint, rounded up.
fn radius(iv: &Interval) -> f64 {
    up(iv.hi - iv.mid()).max(up(iv.mid() - iv.lo))
}

impl Spin {
    /// Rotations smaller than this per step are below any length scale we
    /// can represent (1e-150 rad times any f64 distance underflows the
    /// distances' own precision) and are treated as none.
    const NEGLIGIBLE: f64 = 1.0e-150;

    /// Whether the rotation vector `theta` turns the frame at all (the
    /// constructors let no NaN through).
    fn turns(theta: &Vector3<f64>) -> bool {
        theta.norm() > Spin::NEGLIGIBLE
    }

    fn new(theta: &Vector3<f64>, start: &Matrix3<f64>, arm: &Vector3<f64>) -> Option<Spin> {
        if !Spin::turns(theta) {
            return None;
        }
        let (angle, k) = Spin::unit_axis(theta)?;
        // The products `K·R0`, `K²·R0`, `K·arm`, `K²·arm` in plain `f64`
        // from the axis' midpoints, with one error bound per group: interval
        // products cost several times more, and every collider motion of a
        // step is built here (most are never searched). With `w` the widest
        // axis entry and `S` a column's absolute sum, an entry of
        // `K·x` is off by at most `(w + γ₂)·S` and one of
        // `K²·x = k·(k·x) − x` by at most `(2w + 6u)·S` to first order
        // (`u = 2⁻⁵³`, `γₙ ≈ n·u`); `(4w + 16u)·S` covers both with room
        // for the second-order terms.
        let w = k.iter().map(|iv| iv.width()).fold(0.0, f64::max);
        let kmid = k.map(|iv| iv.mid());
        let rate = 4.0 * w + 16.0 * (0.5 * f64::EPSILON);
        let skew = |x: &Vector3<f64>| kmid.cross(x);
        let square = |x: &Vector3<f64>| kmid * kmid.dot(x) - x;
        let mut rot_k = Matrix3::zeros();
        let mut rot_k2 = Matrix3::zeros();
        let mut widest_column = 0.0f64;
        for j in 0..3 {
            let column = start.column(j).into_owned();
            rot_k.set_column(j, &skew(&column));
            rot_k2.set_column(j, &square(&column));
            widest_column = widest_column.max(column.abs().sum());
        }
        Some(Spin {
            angle: angle.mid(),
            angle_err: radius(&angle),
            rot_k,
            rot_k2,
            rot_err: bound(rate * widest_column),
            arm_k: skew(arm),
            arm_k2: square(arm),
            arm_err: bound(rate * arm.abs().sum()),
        })
    }

    /// `|θ|` and the unit axis `θ/|θ|`, enclosed.
    fn unit_axis(theta: &Vector3<f64>) -> Option<(Interval, Vector3<Interval>)> {
        let t = theta.map(Interval::point);
        let angle = (t.x.sqr() + t.y.sqr() + t.z.sqr()).sqrt().ok()?;
        let inv = angle.recip().ok()?;
        Some((angle, t.map(|x| x * inv)))
    }

    /// `(sin φ, 1 − cos φ)` over the node, and the sum of their largest
    /// magnitudes (which scales the prepared products' error radii).
    fn angle_terms<E: Enclosure>(&self, tau: E) -> (E, E, f64) {
        let phi = (tau * self.angle).widen(up(self.angle_err * tau.range().mag()));
        let (s, cos) = phi.sin_cos();
        let c = E::one() - cos;
        let mag = up(s.range().mag() + c.range().mag());
        (s, c, mag)
    }

    /// `R(τ)` over the node, from `R0` and the angle terms.
    fn rotation<E: Enclosure>(&self, start: &Matrix3<f64>, s: E, c: E, mag: f64) -> Matrix3<E> {
        let slack = up(self.rot_err * mag);
        Matrix3::from_fn(|i, j| {
            s.scaled_sum(
                self.rot_k[(i, j)],
                c,
                self.rot_k2[(i, j)],
                start[(i, j)],
                slack,
            )
        })
    }

    /// The turned arm over the node.
    fn arm<E: Enclosure>(&self, arm: &Vector3<f64>, s: E, c: E, mag: f64) -> Vector3<E> {
        let slack = up(self.arm_err * mag);
        Vector3::from_fn(|i, _| s.scaled_sum(self.arm_k[i], c, self.arm_k2[i], arm[i], slack))
    }
}

/// A prepared turn with what it was made from: the rotation vector, the
/// start matrix and the arm.
type TurnEntry = (Vector3<f64>, Matrix3<f64>, Vector3<f64>, Spin);

/// Whether two lists of numbers are the same bit for bit (`-0.0` and `0.0`
/// are not: the products keep the sign).
fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// The turns prepared last ([`Motion::turn_products`]), by what they were
/// made from: a step's searches enclose the same motion again and again
/// (a hit, its stop, a touching pair's proof), each in a query of its own.
/// A handful, looked up by comparing what they were made from: next to
/// making a turn's products (about 0.7 k instructions) that costs little.
#[derive(Debug, Default)]
pub(crate) struct TurnMemo {
    entries: Vec<TurnEntry>,
    /// The entry the next new turn replaces, once all are taken.
    next: usize,
}

impl TurnMemo {
    const SIZE: usize = 4;

    /// The products kept for the turn `motion` makes, if any.
    fn find(&self, motion: &Motion) -> Option<Spin> {
        self.entries
            .iter()
            .find(|(rotation, start, arm, _)| {
                same_bits(rotation.as_slice(), motion.rotation.as_slice())
                    && same_bits(arm.as_slice(), motion.arm.as_slice())
                    && same_bits(start.as_slice(), motion.start_matrix.as_slice())
            })
            .map(|&(.., spin)| spin)
    }

    /// Keeps `spin`, made for `motion`'s turn, in place of the oldest entry
    /// once all are taken.
    fn keep(&mut self, motion: &Motion, spin: Spin) {
        let entry = (motion.rotation, motion.start_matrix, motion.arm, spin);
        if self.entries.len() < TurnMemo::SIZE {
            self.entries.push(entry);
        } else {
            self.entries[self.next] = entry;
        }
        self.next = (self.next + 1) % TurnMemo::SIZE;
    }
}

/// A rigid frame's motion over one step: a polynomial path of the centre of
/// mass and a constant angular velocity about it (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// Rotation centre (body centre of mass) at `τ = 0`, world, metres.
    center: Point3<f64>,
    /// The frame's origin minus the centre at `τ = 0`, metres.
    arm: Vector3<f64>,
    /// The frame's orientation at `τ = 0`.
    start_rotation: UnitQuaternion<f64>,
    /// The same as a matrix, taken as exact.
    start_matrix: Matrix3<f64>,
    /// The centre's linear displacement over the step, `v·dt`, metres.
    displacement: Vector3<f64>,
    /// The centre's quadratic displacement, `½·a·dt²`, metres.
    bend: Vector3<f64>,
    /// The step's rotation vector `ω·dt`, radians.
    rotation: Vector3<f64>,
    /// The step length, seconds (0 for a fixed frame).
    dt: f64,
    /// The frame turns: `|rotation|` is above `Spin::NEGLIGIBLE`.
    turning: bool,
}

fn check_vector(what: &'static str, v: &Vector3<f64>) -> Result<(), CcdError> {
    for x in v.iter() {
        check_finite(what, *x)?;
    }
    Ok(())
}

fn check_pose(what: &'static str, pose: &Isometry3<f64>) -> Result<(), CcdError> {
    check_vector(what, &pose.translation.vector)?;
    for x in pose.rotation.coords.iter() {
        check_finite(what, *x)?;
    }
    let norm = pose.rotation.coords.norm();
    if !(0.5..=2.0).contains(&norm) {
        return Err(CcdError::BadParameter {
            what,
            value: norm,
            expected: "a unit quaternion",
        });
    }
    Ok(())
}

impl Motion {
    /// A frame that does not move.
    pub fn fixed(pose: Isometry3<f64>) -> Result<Motion, CcdError> {
        Motion::from_velocities(
            pose,
            Point3::from(pose.translation.vector),
            Vector3::zeros(),
            Vector3::zeros(),
            0.0,
        )
    }

    /// A frame starting at `start`, its body's centre of mass at `center`
    /// (world, metres), moving at `linvel` (m/s) and turning at `angvel`
    /// (rad/s, about the centre) for `dt` seconds.
    pub fn from_velocities(
        start: Isometry3<f64>,
        center: Point3<f64>,
        linvel: Vector3<f64>,
        angvel: Vector3<f64>,
        dt: f64,
    ) -> Result<Motion, CcdError> {
        check_pose("start pose", &start)?;
        check_vector("centre of mass", &center.coords)?;
        check_vector("linear velocity", &linvel)?;
        check_vector("angular velocity", &angvel)?;
        check_finite("dt", dt)?;
        if dt < 0.0 {
            return Err(CcdError::BadParameter {
                what: "dt",
                value: dt,
                expected: "dt >= 0 seconds",
            });
        }
        let rotation = angvel * dt;
        let displacement = linvel * dt;
        check_vector("linear velocity × dt", &displacement)?;
        check_vector("angular velocity × dt", &rotation)?;
        Ok(Motion::assemble(&start, center, displacement, rotation, dt))
    }

    /// The motion from checked parts: the frame starts at `start`, its
    /// centre at `center`, which moves by `displacement` and turns by
    /// `rotation` (radians) over `dt` seconds.
    fn assemble(
        start: &Isometry3<f64>,
        center: Point3<f64>,
        displacement: Vector3<f64>,
        rotation: Vector3<f64>,
        dt: f64,
    ) -> Motion {
        let start_rotation = UnitQuaternion::new_normalize(start.rotation.into_inner());
        let start_matrix = *start_rotation.to_rotation_matrix().matrix();
        let arm = start.translation.vector - center.coords;
        Motion {
            center,
            arm,
            start_rotation,
            start_matrix,
            displacement,
            bend: Vector3::zeros(),
            rotation,
            dt,
            turning: Spin::turns(&rotation),
        }
    }

    /// The turn's products that every enclosed pose reads (`None` for a
    /// frame that does not turn), taken from `memo` when a motion with the
    /// same turn was prepared lately, and left there. They are kept apart
    /// from the motion, by whoever encloses it again and again (a search's
    /// frames): most motions a step builds are only boxed and bounded,
    /// never enclosed, and a motion is copied often (a `Spin` would double
    /// its size).
    pub(crate) fn turn_products(&self, memo: &mut TurnMemo) -> Option<Spin> {
        if !self.turning {
            return None;
        }
        memo.find(self).or_else(|| {
            let made = self.made_spin();
            if let Some(spin) = made {
                memo.keep(self, spin);
            }
            made
        })
    }

    /// The turn's products, made now.
    fn made_spin(&self) -> Option<Spin> {
        Spin::new(&self.rotation, &self.start_matrix, &self.arm)
    }

    /// The turn's products for an enclosed pose over `span`: `None` where
    /// the frame has not turned (it does not turn, or `span` is the start).
    /// `prepared` when given ([`Motion::turn_products`]), else made into
    /// `fresh`.
    fn spin_over<'a>(
        &self,
        span: TimeSpan,
        prepared: Option<&'a Spin>,
        fresh: &'a mut Option<Spin>,
    ) -> Option<&'a Spin> {
        if !self.turning || at_start(span) {
            return None;
        }
        if prepared.is_some() {
            return prepared;
        }
        *fresh = self.made_spin();
        fresh.as_ref()
    }

    /// [`Trajectory::pose`], with the turn's products `prepared` by
    /// [`Motion::turn_products`] (`None`: made for this call).
    pub(crate) fn pose_with<E: Enclosure>(
        &self,
        span: TimeSpan,
        prepared: Option<&Spin>,
    ) -> Pose<E> {
        let tau = E::time(span);
        let center = self.center_at(tau);
        let mut fresh = None;
        let Some(spin) = self.spin_over(span, prepared, &mut fresh) else {
            return Pose {
                rotation: self.start_matrix.map(E::constant),
                translation: center + self.arm.map(E::constant),
            };
        };
        let (s, c, mag) = spin.angle_terms(tau);
        Pose {
            rotation: spin.rotation(&self.start_matrix, s, c, mag),
            translation: center + spin.arm(&self.arm, s, c, mag),
        }
    }

    /// [`Trajectory::origin`], with the turn's products as in
    /// [`Motion::pose_with`].
    pub(crate) fn origin_with<E: Enclosure>(
        &self,
        span: TimeSpan,
        prepared: Option<&Spin>,
    ) -> Vector3<E> {
        let tau = E::time(span);
        let center = self.center_at(tau);
        if !self.turning || at_start(span) {
            return center + self.arm.map(E::constant);
        }
        if self.arm == Vector3::zeros() {
            // The origin is the rotation centre: turning moves it not.
            return center;
        }
        let mut fresh = None;
        match self.spin_over(span, prepared, &mut fresh) {
            None => center + self.arm.map(E::constant),
            Some(spin) => {
                let (s, c, mag) = spin.angle_terms(tau);
                center + spin.arm(&self.arm, s, c, mag)
            }
        }
    }

    /// The same motion with a constant linear acceleration `linacc` (m/s²)
    /// of the centre, e.g. gravity.
    pub fn with_acceleration(mut self, linacc: Vector3<f64>) -> Result<Motion, CcdError> {
        check_vector("linear acceleration", &linacc)?;
        self.bend = linacc * (0.5 * self.dt * self.dt);
        check_vector("linear acceleration × dt²", &self.bend)?;
        Ok(self)
    }

    /// The constant-velocity motion that takes the frame from `start` to
    /// `end` in `dt` seconds, turning about `local_center` (the body's centre
    /// of mass in the frame's coordinates).
    ///
    /// `angvel_hint` (rad/s) chooses among the rotations that reach `end`:
    /// the one whose rotation vector is nearest `angvel_hint·dt`, so a body
    /// that spun several turns in the step keeps its whole turns. Pass zero
    /// for the shortest rotation.
    pub fn from_poses(
        start: Isometry3<f64>,
        end: Isometry3<f64>,
        local_center: Point3<f64>,
        dt: f64,
        angvel_hint: Vector3<f64>,
    ) -> Result<Motion, CcdError> {
        check_pose("start pose", &start)?;
        check_pose("end pose", &end)?;
        check_vector("local centre of mass", &local_center.coords)?;
        check_vector("angular velocity hint", &angvel_hint)?;
        check_finite("dt", dt)?;
        if dt <= 0.0 {
            return Err(CcdError::BadParameter {
                what: "dt",
                value: dt,
                expected: "dt > 0 seconds",
            });
        }
        let c0 = start * local_center;
        let c1 = end * local_center;
        let q0 = UnitQuaternion::new_normalize(start.rotation.into_inner());
        let q1 = UnitQuaternion::new_normalize(end.rotation.into_inner());
        let theta = whole_turns(&(q1 * q0.inverse()).scaled_axis(), &(angvel_hint * dt));
        check_vector("centre of mass", &c0.coords)?;
        check_vector("rotation over the step", &theta)?;
        Ok(Motion::assemble(&start, c0, c1 - c0, theta, dt))
    }

    /// The motion of a frame fixed to this one at `local` (the second
    /// frame's pose in this frame's coordinates, metres), e.g. a compound
    /// shape's part: it turns about the same centre at the same rate, so
    /// `with_local_frame(local).pose_at(τ) = pose_at(τ) · local` (up to the
    /// rounding of composing the start pose once, in `f64`).
    ///
    /// Gap functions that need the part's pose *enclosed* compose
    /// [`Trajectory::pose`] of this frame with `local` in enclosure
    /// arithmetic instead, so that no rounding escapes.
    pub fn with_local_frame(&self, local: &Isometry3<f64>) -> Motion {
        let mut motion = *self;
        motion.arm = self.arm + self.start_rotation * local.translation.vector;
        motion.start_rotation =
            UnitQuaternion::new_normalize((self.start_rotation * local.rotation).into_inner());
        motion.start_matrix = *motion.start_rotation.to_rotation_matrix().matrix();
        motion
    }

    /// The same motion moved by a constant `offset` (world, metres) at every
    /// time.
    pub fn shifted(&self, offset: Vector3<f64>) -> Motion {
        let mut motion = *self;
        motion.center += offset;
        motion
    }

    /// The step length in seconds (0 for a fixed frame).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The rotation centre at `τ = 0`.
    pub fn center(&self) -> Point3<f64> {
        self.center
    }

    /// The frame's orientation at `τ = 0`, as the matrix the enclosures use.
    pub fn start_rotation_matrix(&self) -> Matrix3<f64> {
        self.start_matrix
    }

    /// The step's rotation vector `ω·dt`, radians.
    pub fn rotation(&self) -> Vector3<f64> {
        self.rotation
    }

    /// The centre's displacement over the whole step (`d + b`), metres.
    pub fn displacement(&self) -> Vector3<f64> {
        self.displacement + self.bend
    }

    /// How fast the world point `at`, carried by the frame at step fraction
    /// `tau`, moves, metres per step: the centre's mean velocity over the
    /// step plus the turn's about where the centre is at `tau` (the
    /// acceleration's share left out: an estimate, for guesses).
    pub fn point_velocity(&self, at: &Vector3<f64>, tau: f64) -> Vector3<f64> {
        let centre = self.center.coords + self.displacement() * tau;
        self.displacement() + self.rotation.cross(&(at - centre))
    }

    /// True when the frame turns during the step (a turn below any length
    /// scale, see `Spin::NEGLIGIBLE`, counts as none).
    pub fn turns(&self) -> bool {
        self.turning
    }

    /// True when turning moves the frame's origin: the frame turns and
    /// its origin is not its rotation centre. (Only then does an enclosed
    /// origin read the turn's products.)
    pub(crate) fn origin_turns(&self) -> bool {
        self.turning && self.arm != Vector3::zeros()
    }

    /// True when the frame neither moves nor turns.
    pub fn is_fixed(&self) -> bool {
        !self.turns() && self.displacement == Vector3::zeros() && self.bend == Vector3::zeros()
    }

    /// An upper bound on how far any point within `radius` metres of the
    /// frame's origin travels from its start position during the step.
    pub fn travel_bound(&self, radius: f64) -> f64 {
        padded(self.displacement.norm() + self.bend.norm() + self.turning_chord(radius))
    }

    /// An upper bound on how far any point within `radius` metres of the
    /// frame's origin strays, over the times `span`, from the segment
    /// between its positions at the two ends of `span` (half-width `h`):
    /// the centre's `c(τ) = c₀ + v·τ + w·τ²` leaves its chord by
    /// `|w|·(τ − lo)·(hi − τ) ≤ |w|·h²`, and a point `ρ` from the centre,
    /// turning through `φ = 2·|θ|·h`, leaves its chord by the sagitta
    /// `ρ·(1 − cos(φ/2))` (at most `2ρ` once `φ/2` passes a right angle).
    /// A body flying straight strays not at all.
    pub(crate) fn stray_within(&self, span: TimeSpan, radius: f64) -> f64 {
        let (_, h) = span.center_radius();
        let bend = self.bend.norm() * h * h;
        let reach = self.arm.norm() + radius;
        let half_turn = self.rotation.norm() * h;
        // `1 − cos x = 2·sin²(x/2)`, without the cancellation.
        let sagitta = if half_turn < FRAC_PI_2 {
            2.0 * reach * (0.5 * half_turn).sin().powi(2)
        } else {
            2.0 * reach
        };
        padded(bend + sagitta) + 1.0e-12 * reach
    }

    /// How far a point at `local` in this frame (and everything within
    /// `radius` of it) stays from the rotation centre, at every time, metres:
    /// turning does not change it.
    pub fn reach(&self, local: &Vector3<f64>, radius: f64) -> f64 {
        let arm = (self.arm + self.start_matrix * local).norm();
        padded(arm + radius) * (1.0 + 1.0e-12)
    }

    /// A lower bound of the distance between this frame's rotation centre
    /// and `other`'s over the times `span`, metres; a few dozen flops, no
    /// rotation (see [`Motion::centres_offset`]).
    pub fn centres_gap(&self, other: &Motion, span: TimeSpan) -> f64 {
        let (at_middle, stray) = self.centres_offset(other, span, &Vector3::zeros());
        at_middle.norm() - stray
    }

    /// Where `other`'s rotation centre is in this frame's coordinates (from
    /// its origin) at the middle of `span`, and a bound on how far it strays
    /// from there over the span, metres; `None` when this frame turns (its
    /// coordinates then turn too).
    pub fn centre_seen_from(&self, other: &Motion, span: TimeSpan) -> Option<(Vector3<f64>, f64)> {
        if self.turns() {
            return None;
        }
        // A frame that does not turn has its origin at `c(τ) + arm`.
        let (at_middle, stray) = other.centres_offset(self, span, &self.arm);
        Some((self.start_matrix.tr_mul(&at_middle), stray))
    }

    /// `d(m) − shift` for the centres' offset `d(τ) = c(τ) − c_other(τ)` at
    /// the middle `m` of `span`, and a bound on `|d(τ) − d(m)|` over the span
    /// plus the rounding of both. With `d(τ) = d₀ + v·τ + w·τ²`,
    /// `|d(τ) − d(m)| = |τ − m|·|v + w·(τ + m)| ≤ h·(|v| + |w|·(2m + h))`
    /// (`h` the half-width).
    fn centres_offset(
        &self,
        other: &Motion,
        span: TimeSpan,
        shift: &Vector3<f64>,
    ) -> (Vector3<f64>, f64) {
        let d0 = self.center.coords - other.center.coords;
        let v = self.displacement - other.displacement;
        let w = self.bend - other.bend;
        let (m, h) = span.center_radius();
        let at_middle = d0 + v * m + w * (m * m) - shift;
        let (v, w) = (v.norm(), w.norm());
        let drift = h * (v + w * (2.0 * m.abs() + h));
        // Every term is rounded a few times (a rotation by an orthonormal
        // matrix too): 1e-12 of the sizes involved covers that many times
        // over.
        let sizes = self.center.coords.norm() + other.center.coords.norm() + shift.norm() + v + w;
        (
            at_middle,
            padded(drift) + 1.0e-12 * sizes + f64::MIN_POSITIVE,
        )
    }

    /// An upper bound on how much the distance between a point within
    /// `radius` of this frame's origin and a point within `other_radius`
    /// of `other`'s changes during the step: their centres' relative
    /// motion plus both turning chords. Two bodies flying side by side
    /// barely move relative to each other, however fast they go.
    pub fn relative_travel_bound(&self, radius: f64, other: &Motion, other_radius: f64) -> f64 {
        let linear =
            (self.displacement - other.displacement).norm() + (self.bend - other.bend).norm();
        padded(linear + self.turning_chord(radius) + other.turning_chord(other_radius))
    }

    /// [`Self::relative_speed_bound`] along a unit direction, for many
    /// directions: see [`SpeedAlong`].
    pub fn relative_speed_along(
        &self,
        radius: f64,
        other: &Motion,
        other_radius: f64,
    ) -> SpeedAlong {
        let reach = |m: &Motion, radius: f64| (m.arm.norm() + radius, m.rotation);
        SpeedAlong {
            linear: self.displacement - other.displacement,
            bend: self.bend - other.bend,
            turns: [reach(self, radius), reach(other, other_radius)],
        }
    }

    /// An upper bound on how fast a point within `radius` of this frame's
    /// origin and a point within `other_radius` of `other`'s move against
    /// each other, metres per step (per unit of `τ`), at every time of the
    /// step: the centres' relative velocity `d + 2·b·τ` (at most
    /// `|d| + 2·|b|`) plus each point's turning speed `ρ·|θ|`. The distance
    /// between two shapes changes no faster.
    pub fn relative_speed_bound(&self, radius: f64, other: &Motion, other_radius: f64) -> f64 {
        let linear =
            (self.displacement - other.displacement).norm() + 2.0 * (self.bend - other.bend).norm();
        let rates = self.turning_rate(radius) + other.turning_rate(other_radius);
        padded(padded(linear) + rates)
    }

    /// A bound on how much `n·(p − q)` grows over the step (`n` a unit
    /// direction), for any point `p` within `radius` of this frame's
    /// origin and `q` within `other_radius` of `other`'s: how much deeper
    /// two shapes can get along `n`, pointing from this one towards the
    /// other. Signed: a pair flying apart along `n` faster than its turns
    /// bring points back gets 0, however fast it goes.
    ///
    /// The centres' relative motion along `n` is `a·τ + b·τ²` and each
    /// turning chord at most `ρ·|θ|·τ` (`ρ` the reach from the centre), so
    /// the growth is at most `(a + k)·τ + max(b, 0)·τ²`, largest at one
    /// end of the step. Never more than the unsigned bound (centres' motion
    /// along `n` in absolute value plus the chords capped at `2ρ`), which
    /// is the better one for whole turns.
    pub fn relative_approach_along(
        &self,
        n: &Vector3<f64>,
        radius: f64,
        other: &Motion,
        other_radius: f64,
    ) -> f64 {
        let a = (self.displacement - other.displacement).dot(n);
        let b = (self.bend - other.bend).dot(n);
        let unsigned = padded(
            a.abs() + b.abs() + self.turning_chord(radius) + other.turning_chord(other_radius),
        );
        let rates = self.turning_rate(radius) + other.turning_rate(other_radius);
        // Each term is rounded a few times: 1e-12 of their sizes is far
        // more than that.
        let slack = 1.0e-12 * (a.abs() + b.abs() + rates) + f64::MIN_POSITIVE;
        let signed = (a + b.max(0.0) + rates + slack).max(0.0);
        signed.min(unsigned)
    }

    /// Whether `n·p − n·q` stays within `budget` (metres) of its largest
    /// start value over the whole step, where `p` ranges over the convex
    /// hull of `points` (this frame's coordinates) and `q` over that of
    /// `other_points` (`other`'s): whether two convex shapes with those
    /// cores get at most `budget` deeper along `n` (unit, from this shape
    /// towards the other). A rounding moves with its core and drops out.
    /// `false` also when it cannot tell.
    ///
    /// The question [`Motion::relative_approach_along`] answers with chords
    /// about the whole reach, answered point by point: each point advances
    /// along `n` by exactly `n·d·τ + n·b·τ² + A·sin φτ + B·(1 − cos φτ)`
    /// (Rodrigues, `φ = |θ|`), and a hull's support is its farthest
    /// point's, so it moves by the largest advance less how far behind
    /// the farthest point each point starts (a capsule's far end may swing
    /// towards a wall it is nowhere near). The advances are sampled at up
    /// to 64 times and bounded between samples by their curvature: a
    /// capsule bouncing off a wall while it spins is seen to leave it, even
    /// with no budget at all (a pair held at its allowed depth).
    pub fn points_approach_within(
        &self,
        n: &Vector3<f64>,
        points: &[Vector3<f64>],
        other: &Motion,
        other_points: &[Vector3<f64>],
        budget: f64,
    ) -> bool {
        let finite = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
        if points.is_empty()
            || other_points.is_empty()
            || budget.is_nan()
            || budget < 0.0
            || !finite(n)
            || !points.iter().chain(other_points).all(finite)
        {
            return false;
        }
        let ours = Advance::new(self, n, points);
        let theirs = Advance::new(other, &-n, other_points);
        // Each advance takes a few dozen roundings of terms no larger than
        // `size` (libm's sine and cosine within an ulp): 1e-12 of it
        // covers them many times over. The start's growth is 0 exactly.
        let slack = 1.0e-12 * (ours.size + theirs.size) + f64::MIN_POSITIVE;
        let (lin, quad) = (ours.lin + theirs.lin, ours.quad + theirs.quad);
        let turning = ours.curvature + theirs.curvature;
        let curvature = turning + 2.0 * quad.abs();
        // Cells fine enough for the interpolation bound below to cost at
        // most half the budget, 2 to 64 of them.
        let wanted = (curvature / (4.0 * budget.max(1.0e-4))).sqrt();
        let cells = if wanted.is_finite() {
            wanted.ceil().clamp(2.0, 64.0) as usize
        } else {
            64
        };
        let h = 1.0 / cells as f64;
        let between = padded(curvature * h * h / 8.0);
        let path = |t: f64| lin * t + quad * t * t;
        // The samples, in order: `τ = 0, h, 2h, …`.
        let (mut our_turn, mut their_turn) = (
            TurnSamples::new(ours.phi, h),
            TurnSamples::new(theirs.phi, h),
        );
        let mut next = || {
            let a = ours.next_turn(&mut our_turn, h);
            let b = theirs.next_turn(&mut their_turn, h);
            (a.0 + b.0, a.1 + b.1)
        };
        let mut before = 0.0f64;
        let mut ahead = next();
        for k in 1..=cells {
            let (t0, t) = ((k - 1) as f64 * h, k as f64 * h);
            // On each cell the greatest growth is at most the better of
            // two convex bounds, each largest at an end: the lines through
            // the samples plus curvature·h²/8, and the tangents at the
            // left sample plus curvature·h²/2 (which also holds where the
            // growth starts at 0 and the budget is 0: a pair leaving
            // along `n`). The path's own tangent bound takes `|quad|`, so
            // that it is convex too.
            let here = next();
            let now = path(t) + here.0;
            let tangent = path(t0)
                + (lin + 2.0 * quad * t0) * h
                + quad.abs() * h * h
                + ahead.1
                + padded(turning * h * h / 2.0);
            // `slack` covers the roundings of a sample; `up` the last sum.
            let now = up(now + slack);
            let lines = up(before.max(now) + between);
            let tangents = before.max(up(tangent + slack));
            // (A NaN from overflowing terms proves nothing.)
            if lines.is_nan() || tangents.is_nan() || lines.min(tangents) > budget {
                return false;
            }
            before = now;
            ahead = here;
        }
        true
    }

    /// How far the turn alone moves a point within `radius` of the frame's
    /// origin, per unit of `τ`: its distance from the axis, at most
    /// `|arm| + radius`, times the step's angle (rounded up).
    fn turning_rate(&self, radius: f64) -> f64 {
        padded((self.arm.norm() + radius) * self.rotation.norm())
    }

    /// How far the turn alone moves a point within `radius` of the frame's
    /// origin: it is at most `|arm| + radius` from the axis, and its chord
    /// is at most that distance times `min(angle, 2)`.
    fn turning_chord(&self, radius: f64) -> f64 {
        (self.arm.norm() + radius) * self.rotation.norm().min(2.0)
    }

    /// The centre of mass over the node.
    fn center_at<E: Enclosure>(&self, tau: E) -> Vector3<E> {
        let c = &self.center.coords;
        // `c + d·τ + b·τ²` per coordinate, one fused rounding bound each.
        match (
            self.displacement == Vector3::zeros(),
            self.bend == Vector3::zeros(),
        ) {
            (true, true) => c.map(E::constant),
            (_, true) => Vector3::from_fn(|i, _| {
                tau.scaled_sum(self.displacement[i], E::zero(), 0.0, c[i], 0.0)
            }),
            _ => {
                let tau2 = tau.sqr();
                Vector3::from_fn(|i, _| {
                    tau.scaled_sum(self.displacement[i], tau2, self.bend[i], c[i], 0.0)
                })
            }
        }
    }
}

/// A bound of a few rounded operations on non-negative terms, padded up
/// (eight ulps and the smallest normal).
fn padded(x: f64) -> f64 {
    x * (1.0 + 8.0 * f64::EPSILON) + f64::MIN_POSITIVE
}

/// How fast two points within given radii of two frames' origins move
/// against each other along a unit direction `n` (world axes), at every
/// time of the step, metres per step ([`Motion::relative_speed_along`]):
/// the centres' relative velocity along `n`, and each point's turning
/// velocity `θ × r` along `n`, which is `r·(n × θ)`: at most `ρ·|n × θ|`.
/// A spin about an axis near `n` barely moves the shapes along it. What
/// does not depend on `n` is taken once (conservative advancement asks
/// along a new direction each step).
#[derive(Clone, Copy, Debug)]
pub struct SpeedAlong {
    linear: Vector3<f64>,
    bend: Vector3<f64>,
    /// Each side's reach from its turning axis (`|arm| + radius`) and its
    /// rotation vector.
    turns: [(f64, Vector3<f64>); 2],
}

impl SpeedAlong {
    /// The bound along the unit direction `n`.
    pub fn at(&self, n: &Vector3<f64>) -> f64 {
        let linear = self.linear.dot(n).abs() + 2.0 * self.bend.dot(n).abs();
        let turning =
            |(reach, rotation): (f64, Vector3<f64>)| padded(reach * n.cross(&rotation).norm());
        padded(padded(linear) + turning(self.turns[0]) + turning(self.turns[1]))
    }
}

/// Of the rotation vectors `axis·(angle + 2πn)` that give the same rotation
/// as `base`, the one nearest `hint` (both in radians).
fn whole_turns(base: &Vector3<f64>, hint: &Vector3<f64>) -> Vector3<f64> {
    let angle = base.norm();
    let axis = if angle > 1.0e-12 {
        base / angle
    } else if hint.norm() > 0.0 {
        hint.normalize()
    } else {
        return *base;
    };
    let along = axis.dot(hint);
    let n = ((along - angle) / TAU).round();
    if n == 0.0 || !n.is_finite() {
        *base
    } else {
        axis * (angle + TAU * n)
    }
}

impl Trajectory for Motion {
    fn pose<E: Enclosure>(&self, span: TimeSpan) -> Pose<E> {
        self.pose_with(span, None)
    }

    fn origin<E: Enclosure>(&self, span: TimeSpan) -> Vector3<E> {
        self.origin_with(span, None)
    }

    fn pose_at(&self, tau: f64) -> Isometry3<f64> {
        let center = self.center.coords + self.displacement * tau + self.bend * (tau * tau);
        // No turn (or one below any length scale, see `Spin::NEGLIGIBLE`),
        // or the step's start, where the frame has not turned yet (the
        // start contacts and boxes ask there, and the turn would cost a
        // sine and a cosine).
        if !self.turning || tau == 0.0 {
            let origin = center + self.arm;
            return Isometry3::from_parts(Translation3::from(origin), self.start_rotation);
        }
        let turn = UnitQuaternion::from_scaled_axis(self.rotation * tau);
        let origin = center + turn * self.arm;
        Isometry3::from_parts(Translation3::from(origin), turn * self.start_rotation)
    }
}

/// Whether `span` is the start of the step itself, where a frame has not
/// turned yet: its rotation is `R0` exactly (every search asks there once
/// whether its pairs touch at the start, and the turning branch would cost
/// a sine and twelve sums).
fn at_start(span: TimeSpan) -> bool {
    span.lo == 0.0 && span.hi == 0.0
}

/// The advance along a direction `n` of some points carried by a motion
/// (see [`Motion::points_approach_within`]): point `i` advances by
/// `lin·τ + quad·τ² + A_i·sin φτ + B_i·(1 − cos φτ)` from a start `behind_i`
/// behind the farthest point along `n`, so the largest of
/// `advance_i − behind_i` is exactly how far their support has moved.
struct Advance {
    lin: f64,
    quad: f64,
    phi: f64,
    /// `(A_i, B_i, behind_i)` per point.
    terms: SmallVec<[(f64, f64, f64); 8]>,
    /// A bound of the second derivative in `τ` of every point's advance by
    /// the turn alone.
    curvature: f64,
    /// A bound of every term's size, for the rounding slack.
    size: f64,
}

impl Advance {
    fn new(motion: &Motion, n: &Vector3<f64>, points: &[Vector3<f64>]) -> Advance {
        let phi = motion.rotation.norm();
        let k = if phi > 0.0 {
            motion.rotation / phi
        } else {
            Vector3::zeros()
        };
        // Per point, from its arm `w` from the rotation centre at the
        // start: `(A, B, n·w)`, the last made how far behind the farthest
        // point it starts once that is known. On the stack up to a box's
        // eight corners: this runs for every pair such a bound is asked of.
        // A motion that does not turn keeps no terms (its samples are 0,
        // see `next_turn`), only their sizes: `A = 0` and `B = −n·w`.
        let mut terms: SmallVec<[(f64, f64, f64); 8]> = SmallVec::new();
        let (mut ahead, mut reach, mut turn) = (f64::NEG_INFINITY, 0.0f64, 0.0f64);
        // `n·(k × w) = (n × k)·w`: the axis's products with `n` made once,
        // not per point.
        let (nk, n_k) = (n.cross(&k), n.dot(&k));
        for p in points {
            let w = motion.arm + motion.start_matrix * p;
            let along = n.dot(&w);
            ahead = ahead.max(along);
            reach = reach.max(w.norm());
            if phi > 0.0 {
                let (a, b) = (nk.dot(&w), n_k * k.dot(&w) - along);
                turn = turn.max(a.abs() + b.abs());
                terms.push((a, b, along));
            } else {
                turn = turn.max(along.abs());
            }
        }
        for term in &mut terms {
            term.2 = ahead - term.2;
        }
        let (lin, quad) = (n.dot(&motion.displacement), n.dot(&motion.bend));
        Advance {
            lin,
            quad,
            phi,
            curvature: padded(phi * phi * turn),
            size: lin.abs() + quad.abs() + turn + 2.0 * reach,
            terms,
        }
    }

    /// [`Advance::farthest_turn`] at the next of `samples`; `(0, 0)`
    /// without a sample for a motion that does not turn (a fixed target),
    /// which moves no point off its start.
    #[inline]
    fn next_turn(&self, samples: &mut TurnSamples, h: f64) -> (f64, f64) {
        if self.phi == 0.0 {
            return (0.0, 0.0);
        }
        self.farthest_turn(samples.next(), h)
    }

    /// At the time whose `sin φτ` and `cos φτ` are `(s, c)`: the greatest
    /// advance of any point by the turn alone, less its start behind the
    /// farthest, and the greatest of the same plus its rate times `h` (the
    /// tangents' values one cell on).
    #[inline]
    fn farthest_turn(&self, (s, c): (f64, f64), h: f64) -> (f64, f64) {
        self.terms.iter().fold(
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
            |(value, tangent), (a, b, behind)| {
                let g = a * s + b * (1.0 - c) - behind;
                let rate = self.phi * (a * c + b * s);
                (value.max(g), tangent.max(g + rate * h))
            },
        )
    }
}

/// `(sin φτ, cos φτ)` at the sample times `τ = 0, h, 2h, …` of
/// [`Motion::points_approach_within`], in turn: each turned from the last
/// by the cell's angle `φh` (angle addition), and libm's own every
/// [`TurnSamples::RESYNC`] samples. libm's call per sample was half a
/// percent of a slab landing on terrain. Each turn costs about four
/// roundings, so a sample is within about 64 ulps of 1 of libm's (and the
/// angles' own rounding grows no faster than libm's argument's); the
/// samples' slack, `1e-12` of the terms' sizes, still covers that many
/// times over.
struct TurnSamples {
    phi: f64,
    h: f64,
    /// The next sample's index.
    k: usize,
    /// The last sample.
    last: (f64, f64),
    /// `(sin φh, cos φh)`.
    step: (f64, f64),
}

impl TurnSamples {
    /// How many samples apart libm is asked again.
    const RESYNC: usize = 16;

    fn new(phi: f64, h: f64) -> TurnSamples {
        TurnSamples {
            phi,
            h,
            k: 0,
            last: (0.0, 1.0),
            step: (phi * h).sin_cos(),
        }
    }

    /// The next sample: at `τ = 0` exactly `(0, 1)`.
    #[inline]
    fn next(&mut self) -> (f64, f64) {
        let (s, c) = self.last;
        let (sh, ch) = self.step;
        self.last = match self.k {
            0 => (0.0, 1.0),
            k if k % TurnSamples::RESYNC == 0 => (self.phi * (k as f64 * self.h)).sin_cos(),
            _ => (s * ch + c * sh, c * ch - s * sh),
        };
        self.k += 1;
        self.last
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The prepared products in interval arithmetic (they enclose the
    /// exact ones), entry by entry: the reference the `f64` bounds must
    /// hold.
    fn interval_products(
        theta: &Vector3<f64>,
        start: &Matrix3<f64>,
        arm: &Vector3<f64>,
    ) -> (
        Matrix3<Interval>,
        Matrix3<Interval>,
        Vector3<Interval>,
        Vector3<Interval>,
    ) {
        let (_, k) = Spin::unit_axis(theta).expect("non-zero axis");
        let zero = Interval::point(0.0);
        let skew = Matrix3::new(zero, -k.z, k.y, k.z, zero, -k.x, -k.y, k.x, zero);
        let k2 = Matrix3::from_fn(|i, j| {
            let kk = k[i] * k[j];
            if i == j {
                kk - Interval::point(1.0)
            } else {
                kk
            }
        });
        let times = |m: &Matrix3<Interval>, r: &Matrix3<f64>| {
            Matrix3::from_fn(|i, j| {
                m[(i, 0)] * r[(0, j)] + m[(i, 1)] * r[(1, j)] + m[(i, 2)] * r[(2, j)]
            })
        };
        let apply = |m: &Matrix3<Interval>, v: &Vector3<f64>| {
            Vector3::from_fn(|i, _| m[(i, 0)] * v.x + m[(i, 1)] * v.y + m[(i, 2)] * v.z)
        };
        (
            times(&skew, start),
            times(&k2, start),
            apply(&skew, arm),
            apply(&k2, arm),
        )
    }

    fn holds(mid: f64, err: f64, iv: &Interval) -> bool {
        mid - err <= iv.lo && iv.hi <= mid + err
    }

    /// A motion from sampled parts: start pose, centre offset, velocities,
    /// acceleration.
    fn sampled_motion(
        origin: [f64; 3],
        turn: [f64; 3],
        center: [f64; 3],
        linvel: [f64; 3],
        angvel: [f64; 3],
        linacc: [f64; 3],
    ) -> Motion {
        let start = Isometry3::new(Vector3::from(origin), Vector3::from(turn));
        let center = Point3::from(Vector3::from(origin) + Vector3::from(center));
        Motion::from_velocities(start, center, linvel.into(), angvel.into(), 1.0 / 60.0)
            .and_then(|m| m.with_acceleration(linacc.into()))
            .expect("finite motion")
    }

    proptest! {
        /// No point of either frame gets deeper along `n` than the signed
        /// bound says, at any sampled time: whatever the spin (whole turns
        /// too), acceleration and offset of the centre.
        #[test]
        fn the_approach_bound_holds_every_point(
            parts in prop::array::uniform6(prop::array::uniform3(-3.0f64..3.0)),
            speeds in prop::array::uniform4(prop::array::uniform3(-400.0f64..400.0)),
            accels in prop::array::uniform2(prop::array::uniform3(-3000.0f64..3000.0)),
            points in prop::array::uniform2(prop::array::uniform3(-1.0f64..1.0)),
            n in prop::array::uniform3(-1.0f64..1.0),
            radii in prop::array::uniform2(0.0f64..2.0),
            spin_scales in prop::array::uniform2(-5i32..1),
        ) {
            let n = Vector3::from(n);
            prop_assume!(n.norm() > 1.0e-3);
            let n = n.normalize();
            let [o1, t1, c1, o2, t2, c2] = parts;
            let [v1, w1, v2, w2] = speeds;
            // Slow turns too, where the centres' motion decides.
            let scaled = |w: [f64; 3], k: i32| w.map(|x| x * 10f64.powi(k));
            let (w1, w2) = (scaled(w1, spin_scales[0]), scaled(w2, spin_scales[1]));
            let m1 = sampled_motion(o1, t1, c1, v1, w1, accels[0]);
            let m2 = sampled_motion(o2, t2, c2, v2, w2, accels[1]);
            // A point within each radius of its frame's origin, in its frame.
            let local = |p: [f64; 3], r: f64| {
                let p = Vector3::from(p);
                Point3::from(p * (r / p.norm().max(1.0)))
            };
            let (p, q) = (local(points[0], radii[0]), local(points[1], radii[1]));
            let bound = m1.relative_approach_along(&n, radii[0], &m2, radii[1]);
            let along = |tau: f64| n.dot(&(m1.pose_at(tau) * p - m2.pose_at(tau) * q));
            let start = along(0.0);
            for k in 1..=64 {
                let tau = k as f64 / 64.0;
                let grown = along(tau) - start;
                prop_assert!(grown <= bound + 1.0e-9 * (1.0 + bound), "τ {tau}: grew {grown} > bound {bound}");
            }
        }

        /// Every exact product lies in its interval enclosure, so an `f64`
        /// bound that holds the whole interval holds the exact value.
        #[test]
        fn prepared_products_hold_the_interval_ones(
            theta in prop::array::uniform3(-300.0f64..300.0),
            scale in -12i32..3,
            axis in prop::array::uniform3(-1.0f64..1.0),
            angle in -7.0f64..7.0,
            arm in prop::array::uniform3(-50.0f64..50.0),
        ) {
            let theta = Vector3::from(theta) * 10f64.powi(scale);
            prop_assume!(theta.norm() > 1.0e-100);
            let axis = Vector3::from(axis);
            prop_assume!(axis.norm() > 1.0e-3);
            let start = *UnitQuaternion::from_scaled_axis(axis.normalize() * angle)
                .to_rotation_matrix()
                .matrix();
            let arm = Vector3::from(arm);
            let spin = Spin::new(&theta, &start, &arm).expect("turning");
            let (rk, rk2, ak, ak2) = interval_products(&theta, &start, &arm);
            for (mid, iv) in spin.rot_k.iter().zip(rk.iter()) {
                prop_assert!(holds(*mid, spin.rot_err, iv), "K·R0 {mid} ± {} vs {iv:?}", spin.rot_err);
            }
            for (mid, iv) in spin.rot_k2.iter().zip(rk2.iter()) {
                prop_assert!(holds(*mid, spin.rot_err, iv), "K²·R0 {mid} ± {} vs {iv:?}", spin.rot_err);
            }
            for (mid, iv) in spin.arm_k.iter().zip(ak.iter()) {
                prop_assert!(holds(*mid, spin.arm_err, iv), "K·arm {mid} ± {} vs {iv:?}", spin.arm_err);
            }
            for (mid, iv) in spin.arm_k2.iter().zip(ak2.iter()) {
                prop_assert!(holds(*mid, spin.arm_err, iv), "K²·arm {mid} ± {} vs {iv:?}", spin.arm_err);
            }
        }
    }

    /// The turn's products kept apart from the motion (a search's frames
    /// keep them, `Motion::turn_products`) enclose bit for bit what the
    /// products made for each call do (a user's motion, enclosed through
    /// `Trajectory`), over the whole step, a node, and the start; a frame
    /// carried by a turning one too, and one whose origin is its rotation
    /// centre (a ball's).
    #[test]
    fn kept_turn_products_enclose_what_fresh_ones_do() {
        use crate::enclosure::Affine;
        let spans = [
            TimeSpan::STEP,
            TimeSpan::new(0.3, 0.45),
            TimeSpan::new(0.0, 0.0),
        ];
        let local = Isometry3::new(Vector3::new(0.2, -0.1, 0.4), Vector3::new(0.3, 0.0, -0.2));
        let mut memo = TurnMemo::default();
        for (center, angvel) in [
            ([0.3, -0.2, 0.1], [4.0, -30.0, 12.0]),
            ([0.0, 0.0, 0.0], [0.0, 700.0, 0.0]),
            ([0.5, 0.5, 0.5], [0.0, 0.0, 0.0]),
        ] {
            let motion = sampled_motion(
                [1.0, 2.0, 3.0],
                [0.1, 0.2, 0.3],
                center,
                [5.0, 0.0, -2.0],
                angvel,
                [0.0; 3],
            );
            for motion in [motion, motion.with_local_frame(&local)] {
                let kept = motion.turn_products(&mut memo);
                assert_eq!(kept.is_some(), motion.turns(), "kept when it turns");
                for span in spans {
                    assert_eq!(
                        motion.pose_with::<Affine>(span, kept.as_ref()),
                        motion.pose::<Affine>(span),
                        "{span:?}"
                    );
                    assert_eq!(
                        motion.origin_with::<Affine>(span, kept.as_ref()),
                        motion.origin::<Affine>(span),
                        "{span:?}"
                    );
                }
            }
        }
    }

    /// Turns prepared through a memo are each their own: motions that
    /// share the rotation but not the start or the arm get their own
    /// products, a turn pushed out of the memo is made anew, and one still
    /// in it is read back.
    #[test]
    fn the_memo_gives_each_turn_its_own_products() {
        let angvel = [3.0, -40.0, 9.0];
        let motions: Vec<Motion> = (0..2 * TurnMemo::SIZE + 2)
            .map(|k| {
                let k = k as f64;
                // Even ones differ in their start, odd ones in their arm.
                let (turn, center) = if k % 2.0 == 0.0 {
                    ([0.1 * k, 0.2, 0.3], [0.3, -0.2, 0.1])
                } else {
                    ([0.0, 0.2, 0.3], [0.3 + 0.1 * k, -0.2, 0.1])
                };
                sampled_motion(
                    [1.0, 2.0, 3.0],
                    turn,
                    center,
                    [5.0, 0.0, -2.0],
                    angvel,
                    [0.0; 3],
                )
            })
            .collect();
        let mut memo = TurnMemo::default();
        // Each in turn, then all again (all pushed out by then), then the
        // last one (still in).
        let order = (0..motions.len())
            .chain(0..motions.len())
            .chain([motions.len() - 1]);
        for i in order {
            let through_memo = motions[i].turn_products(&mut memo);
            let direct = motions[i].made_spin();
            assert!(direct.is_some());
            assert_eq!(through_memo, direct, "motion {i}");
        }
    }
}
