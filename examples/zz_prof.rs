use affine_ccd_scenes as scenes;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let reps: usize = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(10);
    for scene in scenes::all()
        .into_iter()
        .filter(|s| args[1] == "all" || s.name == args[1])
    {
        let mut best = f64::INFINITY;
        for _ in 0..reps {
            let (mut world, setup) = scene.instantiate();
            let mut ccd = affine_ccd::rapier::AffineCcd::default();
            ccd.install(&mut world);
            let t = std::time::Instant::now();
            for step in 0..scene.steps {
                let end_time = (step + 1) as f32 * scene.dt;
                for s in &setup.scripts {
                    s.apply(&mut world, end_time);
                }
                ccd.step(&mut world);
            }
            best = best.min(t.elapsed().as_secs_f64() * 1e3 / scene.steps as f64);
        }
        println!("{:26} {:.4}", scene.name, best);
    }
}
