#[path = "../benches/common/mod.rs"]
mod common;
use affine_ccd::query::{QueryOptions, time_of_impact};
const REPS: usize = 300;
fn main() {
    let k: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2);
    let kinds = common::pair_kinds();
    let cases = common::cases(&kinds[k], 200, 1000 + k as u64);
    let options = QueryOptions {
        epsilon: 1e-4,
        ..QueryOptions::default()
    };
    let t = std::time::Instant::now();
    let mut evals = 0;
    for _ in 0..REPS {
        for c in &cases {
            let r = time_of_impact(
                c.shape1.as_ref(),
                &c.motion1,
                c.shape2.as_ref(),
                &c.motion2,
                &options,
            )
            .unwrap();
            if let Some(t) = r {
                evals += t.stats.pair_evaluations;
            }
        }
    }
    println!(
        "{} query {:?} evals {evals}",
        kinds[k].name,
        t.elapsed() / (REPS as u32 * cases.len() as u32)
    );
}
