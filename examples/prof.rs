#[path = "../benches/common/mod.rs"]
mod common;
use affine_ccd::query::{QueryOptions, time_of_impact};
fn main() {
    let kinds = common::pair_kinds();
    let cases = common::cases(&kinds[0], 200, 1000);
    let options = QueryOptions {
        epsilon: 1e-4,
        ..QueryOptions::default()
    };
    let mut n = 0;
    for _ in 0..200 {
        for c in &cases {
            if time_of_impact(
                c.shape1.as_ref(),
                &c.motion1,
                c.shape2.as_ref(),
                &c.motion2,
                &options,
            )
            .unwrap()
            .is_some()
            {
                n += 1;
            }
        }
    }
    println!("{n}");
}
