use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;
use nbhd::*;
use std::time::Instant;

fn torus(n: usize) -> Vec<[f32; 3]> {
    let mut s = 12345u64;
    let mut r = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let (u, v) = (r() * std::f64::consts::TAU, r() * std::f64::consts::TAU);
            let (rr, a) = (1.0, 0.35);
            [((rr + a * v.cos()) * u.cos()) as f32, ((rr + a * v.cos()) * u.sin()) as f32, (a * v.sin()) as f32]
        })
        .collect()
}

fn main() {
    let n: usize = std::env::args().nth(1).map(|a| a.parse().unwrap()).unwrap_or(1_000_000);
    let pts = torus(n);
    let view = PointsView::from_rows(&pts).unwrap();
    for (name, opts) in [
        ("sliding", BuildOptions { threads: 1, ..Default::default() }),
        ("cyclic", BuildOptions { threads: 1, pivot: PivotPolicy::CyclicMedian, ..Default::default() }),
        ("spread", BuildOptions { threads: 1, pivot: PivotPolicy::SpreadMedian, ..Default::default() }),
    ] {
        let t = Instant::now();
        let tree = KdTree::<f32>::build(&view, &opts).unwrap();
        let tb = t.elapsed();
        let t = Instant::now();
        let table = tree.neighborhoods(Neighborhood::Knn { k: 10 }, &TableOptions { exclude_self: false, threads: 1 }).unwrap();
        let tq = t.elapsed();
        println!("nbhd {name}: build {:?} knn10 {:?} ({} rows) stats {:?}", tb, tq, table.len(), tree.stats());
    }
    let t = Instant::now();
    let kt: ImmutableKdTree<f32, u32, 3, 32> = ImmutableKdTree::new_from_slice(&pts);
    let tb = t.elapsed();
    let t = Instant::now();
    let mut total = 0usize;
    for p in &pts {
        let r = kt.nearest_n::<SquaredEuclidean>(p, std::num::NonZero::new(10).unwrap());
        total += r.len();
    }
    println!("kiddo: build {:?} knn10 {:?} {}", tb, t.elapsed(), total);
}
