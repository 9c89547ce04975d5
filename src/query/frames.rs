//! The frames a search reads poses from: one per moving shape, plus one per
//! compound part met during the search (a frame fixed to its parent at a
//! local pose). Each frame's pose is enclosed once per node, on first use,
//! for every pair that reads it; so are the relative poses composite pairs
//! read, and each frame keeps its last exact pose (at a node's middle).
//! A frame's turn products ([`Motion::turn_products`]) are made on its
//! first enclosed pose and kept with the frame.

use crate::enclosure::{Enclosure, TimeSpan};
use crate::gap::KeptPose;
use crate::hashing::FastMap;
use crate::motion::{Motion, Pose, Spin, TurnMemo, column, row};
use nalgebra::{Isometry3, Matrix3, Vector3};

/// A frame of the search: a body's motion, or a frame fixed to another at
/// a local pose (a compound's part).
#[derive(Debug)]
pub(super) struct FrameDef {
    pub motion: Motion,
    /// The motion's turn products, once its pose is first enclosed (only
    /// a root frame's: a part's pose comes from its parent's).
    turn: Option<Spin>,
    /// The parent frame and this frame's rotation and origin in it.
    pub parent: Option<(u32, Matrix3<f64>, Vector3<f64>)>,
}

impl FrameDef {
    pub fn root(motion: Motion) -> FrameDef {
        FrameDef {
            motion,
            turn: None,
            parent: None,
        }
    }
}

/// The frame tree of one query and its per-node pose cache.
pub(super) struct Frames<E: Enclosure> {
    defs: Vec<FrameDef>,
    poses: Vec<Option<Pose<E>>>,
    /// Per frame: does any pair read its rotation? (Balls read only their
    /// origin, which saves enclosing a rotating matrix per node.)
    rotation_read: Vec<bool>,
    /// (parent frame, part index) → the part's frame.
    child_frames: FastMap<(u32, u32), u32>,
    /// `(to, from, pose of from in to)` for this node.
    relative: Vec<(u32, u32, Pose<E>)>,
    /// Per frame: its last exact pose (`Side::pose_at`).
    kept: Vec<KeptPose>,
    /// Turns prepared by earlier queries (see [`FrameBuffers`]).
    turns: TurnMemo,
}

/// What a query context keeps of its frames between searches: the frame
/// list's buffer and the turns prepared lately.
#[derive(Debug, Default)]
pub(super) struct FrameBuffers {
    pub defs: Vec<FrameDef>,
    pub turns: TurnMemo,
}

impl<E: Enclosure> Frames<E> {
    pub fn new(buffers: &mut FrameBuffers, rotation_read: Vec<bool>) -> Frames<E> {
        let defs = std::mem::take(&mut buffers.defs);
        Frames {
            turns: std::mem::take(&mut buffers.turns),
            poses: vec![None; defs.len()],
            kept: (0..defs.len()).map(|_| KeptPose::default()).collect(),
            defs,
            rotation_read,
            child_frames: FastMap::default(),
            relative: Vec::new(),
        }
    }

    /// Gives back what the query context keeps.
    pub fn into_buffers(self, buffers: &mut FrameBuffers) {
        buffers.defs = self.defs;
        buffers.turns = self.turns;
    }

    pub fn motion(&self, index: u32) -> &Motion {
        &self.defs[index as usize].motion
    }

    /// Where frame `index`'s last exact pose is kept.
    pub fn kept(&self, index: u32) -> &KeptPose {
        &self.kept[index as usize]
    }

    /// Forgets the poses of the last node; a fixed frame's pose is the same
    /// on every node and is kept.
    pub fn begin_node(&mut self) {
        for (pose, frame) in self.poses.iter_mut().zip(&self.defs) {
            if !frame.motion.is_fixed() {
                *pose = None;
            }
        }
        self.relative.clear();
    }

    /// The enclosed pose of frame `index` over the node `span`, enclosed
    /// now if this node has not yet (read it with
    /// [`pose_of`](Frames::pose_of): a pose is 36 enclosures, and copying
    /// it out for every pair cost more than reading it in place).
    pub fn enclose(&mut self, index: u32, span: TimeSpan) {
        let i = index as usize;
        if self.poses[i].is_some() {
            return;
        }
        let pose = match self.defs[i].parent {
            None if !self.rotation_read[i] => {
                // Only the origin is read: the rotation stays at its start.
                let def = &mut self.defs[i];
                if def.turn.is_none() && def.motion.origin_turns() {
                    def.turn = def.motion.turn_products(&mut self.turns);
                }
                let motion = &def.motion;
                let mut pose = Pose::constant(&motion.start_rotation_matrix(), &Vector3::zeros());
                pose.translation = motion.origin_with(span, def.turn.as_ref());
                pose
            }
            None => {
                let def = &mut self.defs[i];
                if def.turn.is_none() {
                    def.turn = def.motion.turn_products(&mut self.turns);
                }
                def.motion.pose_with(span, def.turn.as_ref())
            }
            Some((parent, rotation, origin)) => {
                self.enclose(parent, span);
                let p = self.pose_of(parent);
                Pose {
                    rotation: Matrix3::from_fn(|r, c| {
                        E::dot_f64(row(&p.rotation, r), column(&rotation, c))
                    }),
                    translation: p.transform_point(&origin),
                }
            }
        };
        self.poses[i] = Some(pose);
    }

    /// The pose of frame `index` over this node, enclosed already
    /// ([`enclose`](Frames::enclose)).
    pub fn pose_of(&self, index: u32) -> &Pose<E> {
        self.poses[index as usize]
            .as_ref()
            .expect("a frame's pose is enclosed before it is read")
    }

    /// The pose of frame `from` in frame `to`'s coordinates over the node.
    pub fn relative(&mut self, to: u32, from: u32, span: TimeSpan) -> Pose<E> {
        self.enclose(to, span);
        self.enclose(from, span);
        let kept = self.keep_relative(to, from);
        self.relative[kept].2
    }

    /// [`relative`](Frames::relative) from the two frames' poses on this
    /// node, enclosed already, kept: the index to read it back by
    /// reference with [`kept_relative`](Frames::kept_relative).
    fn keep_relative(&mut self, to: u32, from: u32) -> usize {
        if let Some(kept) = self.relative.iter().position(|r| r.0 == to && r.1 == from) {
            return kept;
        }
        let pose = self.pose_of(to).relative(self.pose_of(from));
        self.relative.push((to, from, pose));
        self.relative.len() - 1
    }

    /// [`keep_relative`](Frames::keep_relative) of `b` in `a` and of `a`
    /// in `b` as `reads` asks, from their poses on this node, enclosed
    /// already. Kept out of line: only a composite's pieces ask, and the
    /// evaluation of every pair runs through its caller.
    #[inline(never)]
    pub fn keep_relatives(&mut self, reads: [bool; 2], [a, b]: [u32; 2]) -> [Option<usize>; 2] {
        [
            reads[0].then(|| self.keep_relative(a, b)),
            reads[1].then(|| self.keep_relative(b, a)),
        ]
    }

    /// A relative pose kept on this node by [`keep_relative`](Frames::keep_relative).
    pub fn kept_relative(&self, kept: usize) -> &Pose<E> {
        &self.relative[kept].2
    }

    /// The frame of part `index` of a compound in frame `parent`.
    pub fn child(&mut self, parent: u32, index: u32, local: &Isometry3<f64>) -> u32 {
        if let Some(&f) = self.child_frames.get(&(parent, index)) {
            return f;
        }
        let motion = self.defs[parent as usize].motion.with_local_frame(local);
        let rotation = *local.rotation.to_rotation_matrix().matrix();
        let id = self.defs.len() as u32;
        self.defs.push(FrameDef {
            motion,
            turn: None,
            parent: Some((parent, rotation, local.translation.vector)),
        });
        self.poses.push(None);
        self.kept.push(KeptPose::default());
        self.rotation_read.push(true);
        self.child_frames.insert((parent, index), id);
        id
    }
}
