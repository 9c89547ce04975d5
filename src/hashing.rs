//! Hash sets and maps keyed by handles and small indices.
//!
//! The stage asks such sets a few dozen times a step (which bodies a
//! pusher's front holds, which it has seen); std's default SipHash, made to
//! resist crafted keys, cost more than the work around it (some 3 % of the
//! instructions of a kinematic-push scene). foldhash's fixed-seed hasher is
//! the one parry's own maps use: fast on integer keys, and the same
//! iteration order on every run.

use foldhash::fast::FixedState;

/// A hash set with foldhash's fixed-seed hasher.
pub(crate) type FastSet<T> = std::collections::HashSet<T, FixedState>;

/// A hash map with foldhash's fixed-seed hasher.
pub(crate) type FastMap<K, V> = std::collections::HashMap<K, V, FixedState>;
