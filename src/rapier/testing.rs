//! What the stage's tests share.

use nalgebra::Vector3;

/// A small deterministic generator of test numbers (xorshift).
pub(crate) struct Numbers(pub u64);

impl Numbers {
    pub fn next(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn vector(&mut self, size: f64) -> Vector3<f64> {
        Vector3::new(
            self.next(-size, size),
            self.next(-size, size),
            self.next(-size, size),
        )
    }
}
