//! Box queries on the k-d tree against a scan over all points: 1,000 boxes of three sizes
//! (about 0.01 %, 1 % and 10 % of the bounding box's volume, centred on random points), one
//! thread, f32, the same answers checked.
//!
//! Run: `cargo run --release --example box_timing -- [set] [boxes]` (default torus-77k, 1000).

use std::time::Instant;

use nbhd::shapes::datasets::Dataset;
use nbhd::shapes::Rng;
use nbhd::NeighborIndex;
use nbhd::{BuildOptions, KdTree, PointsView};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let set_name = args.get(1).map_or("torus-77k", String::as_str);
    let m: usize = args.get(2).and_then(|r| r.parse().ok()).unwrap_or(1000);
    let set: Dataset = set_name.parse().unwrap_or_else(|e| panic!("{e}"));
    let pts: Vec<[f32; 3]> = set.points().iter().map(|p| p.map(|c| c as f32)).collect();
    let view = PointsView::from_rows(&pts).unwrap();
    let tree = KdTree::<f32>::build(&view, &BuildOptions::default()).unwrap();
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in &pts {
        for j in 0..3 {
            lo[j] = lo[j].min(p[j]);
            hi[j] = hi[j].max(p[j]);
        }
    }
    println!("{set_name}: {} points, {m} boxes per size", pts.len());
    let mut rng = Rng::new(7);
    for fraction in [0.0001f32, 0.01, 0.1] {
        let side = fraction.cbrt();
        let boxes: Vec<f32> = (0..m)
            .flat_map(|_| {
                let c = pts[rng.below(pts.len())];
                let half: Vec<f32> = (0..3).map(|j| 0.5 * side * (hi[j] - lo[j])).collect();
                let min: Vec<f32> = (0..3).map(|j| c[j] - half[j]).collect();
                let max: Vec<f32> = (0..3).map(|j| c[j] + half[j]).collect();
                [min, max].concat()
            })
            .collect();
        let t = Instant::now();
        let rows = tree.in_boxes(&boxes, 1).unwrap();
        let tree_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let mut total = 0usize;
        for b in boxes.chunks(6) {
            let inside = pts
                .iter()
                .filter(|p| (0..3).all(|j| b[j] <= p[j] && p[j] <= b[3 + j]))
                .count();
            total += inside;
        }
        let scan_ms = t.elapsed().as_secs_f64() * 1e3;
        assert_eq!(total, rows.total(), "the tree and the scan disagree");
        println!(
            "  {:>7.2} % of the volume: {:>9.1} points per box; tree {tree_ms:>8.2} ms, \
             scan {scan_ms:>8.2} ms ({:.0}x)",
            fraction * 100.0,
            total as f64 / m as f64,
            scan_ms / tree_ms
        );
    }
}
