use affine_ccd_scenes::{Backend, RunOptions, run_scene};
#[test]
fn probe() {
    for scene in affine_ccd_scenes::all() {
        if !scene.effects.settles {
            continue;
        }
        let runs: Vec<_> = [Backend::Off, Backend::Rapier, Backend::Affine]
            .iter()
            .map(|b| run_scene(&scene, *b, &RunOptions::default()).unwrap())
            .collect();
        println!("{}", scene.name);
        for k in 0..runs[0].final_bodies.len() {
            let line: Vec<String> = runs
                .iter()
                .map(|r| {
                    let (_, s) = &r.final_bodies[k];
                    let c = s.com();
                    format!(
                        "({:7.3} {:7.4} {:7.3}) v{:.3}",
                        c.x,
                        c.y,
                        c.z,
                        s.linvel.length()
                    )
                })
                .collect();
            println!(
                "  body {k}: off {} | rapier {} | affine {}",
                line[0], line[1], line[2]
            );
        }
    }
}
