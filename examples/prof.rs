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
    let (mut hit_evals, mut miss_evals, mut hits, mut misses) = (0u64, 0u64, 0u64, 0u64);
    for c in &cases {
        let r = time_of_impact(
            c.shape1.as_ref(),
            &c.motion1,
            c.shape2.as_ref(),
            &c.motion2,
            &options,
        )
        .unwrap();
        match r {
            Some(t) => {
                hits += 1;
                hit_evals += t.stats.pair_evaluations;
            }
            None => {
                misses += 1;
            }
        }
    }
    let _ = &mut miss_evals;
    println!(
        "hits {hits} avg evals {}, misses {misses}",
        hit_evals as f64 / hits as f64
    );
    let t = std::time::Instant::now();
    for _ in 0..100 {
        for c in cases.iter().filter(|c| c.truth.first_contact.is_none()) {
            let _ = time_of_impact(
                c.shape1.as_ref(),
                &c.motion1,
                c.shape2.as_ref(),
                &c.motion2,
                &options,
            );
        }
    }
    println!("miss query {:?}", t.elapsed() / (100 * misses as u32));
    let t = std::time::Instant::now();
    for _ in 0..100 {
        for c in cases.iter().filter(|c| c.truth.first_contact.is_some()) {
            let _ = time_of_impact(
                c.shape1.as_ref(),
                &c.motion1,
                c.shape2.as_ref(),
                &c.motion2,
                &options,
            );
        }
    }
    println!("hit query {:?}", t.elapsed() / (100 * hits as u32));
}
