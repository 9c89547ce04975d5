#[path = "../benches/common/mod.rs"]
mod common;
use affine_ccd::query::{QueryOptions, time_of_impact};
fn main() {
    let kinds = common::pair_kinds();
    let cases = common::cases(&kinds[0], 300, 1000);
    let options = QueryOptions {
        epsilon: 1e-4,
        ..QueryOptions::default()
    };
    let misses: Vec<_> = cases
        .iter()
        .filter(|c| c.truth.first_contact.is_none())
        .collect();
    let t = std::time::Instant::now();
    let mut evals = 0;
    for _ in 0..2000 {
        for c in &misses {
            let r = time_of_impact(
                c.shape1.as_ref(),
                &c.motion1,
                c.shape2.as_ref(),
                &c.motion2,
                &options,
            )
            .unwrap();
            if r.is_some() {
                evals += 1;
            }
        }
    }
    println!(
        "miss query {:?} {evals}",
        t.elapsed() / (2000 * misses.len() as u32)
    );
}
