use latticebuild_geom::field::ScalarField;
use latticebuild_geom::sdf::{self, Aabb, NoExternalSolids, Program};
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let prog = &args[0];
    let f = Program::parse_str(prog).unwrap().field(&NoExternalSolids).unwrap();
    let d: Aabb = if args.len() > 2 { sdf::parse_box(&args[2]).unwrap() } else { f.domain() };
    for n in args[1].split(',').map(|s| s.parse::<usize>().unwrap()) {
        let t = std::time::Instant::now();
        let mesh = sdf::mesh(&f, &d, [n; 3]).unwrap();
        let c = latticebuild_geom::validate::check(&mesh);
        let m = n;
        let mut inside = 0usize;
        let centre = |a: usize, i: usize| d.min[a] + (d.max[a] - d.min[a]) * (i as f64 + 0.5) / m as f64;
        let xs: Vec<f64> = (0..m * m).map(|q| centre(0, q % m)).collect();
        let ys: Vec<f64> = (0..m * m).map(|q| centre(1, q / m)).collect();
        let mut out = vec![0.0; m * m];
        for k in 0..m {
            let zs = vec![centre(2, k); m * m];
            f.eval_points(&xs, &ys, &zs, &mut out);
            inside += out.iter().filter(|v| **v < 0.0).count();
        }
        let counted = d.volume() * inside as f64 / (m * m * m) as f64;
        println!("n={n} mc={:.5} counted={:.5} tris={} wt={} mf={} {:.2}s", c.volume, counted, mesh.triangles.len(), c.watertight, c.manifold, t.elapsed().as_secs_f64());
    }
}
