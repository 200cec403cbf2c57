//! Build time of nbhd's default tree next to kiddo's immutable tree, interleaved, as the
//! minimum and the median of many runs (minimums are what a loaded, shared machine disturbs
//! least). `cargo run --release --example build_timing [set] [reps]`, set as in
//! `nbhd::shapes::datasets::Dataset` (default torus-77k).
use std::time::Instant;

use kiddo::ImmutableKdTree;
use nbhd::shapes::datasets::Dataset;
use nbhd::{BuildOptions, KdTree, PointsView};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("torus-77k", String::as_str);
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(31);
    let set: Dataset = name.parse().unwrap_or_else(|e| panic!("{e}"));
    let pts: Vec<[f32; 3]> = set.points().iter().map(|p| p.map(|c| c as f32)).collect();
    let view = PointsView::from_rows(&pts).unwrap();
    let (mut ours, mut peer) = (Vec::new(), Vec::new());
    for _ in 0..reps {
        let t = Instant::now();
        let tree = KdTree::<f32>::build(
            &view,
            &BuildOptions {
                threads: 1,
                ..Default::default()
            },
        );
        ours.push(t.elapsed().as_secs_f64() * 1e3);
        drop(tree);
        let t = Instant::now();
        let k = ImmutableKdTree::<f32, 3>::new_from_slice(&pts).unwrap();
        peer.push(t.elapsed().as_secs_f64() * 1e3);
        drop(k);
    }
    for v in [&mut ours, &mut peer] {
        v.sort_by(f64::total_cmp);
    }
    println!(
        "{name}: nbhd min {:.2} ms median {:.2} ms; kiddo min {:.2} ms median {:.2} ms; kiddo/nbhd min {:.2} median {:.2}",
        ours[0],
        ours[reps / 2],
        peer[0],
        peer[reps / 2],
        peer[0] / ours[0],
        peer[reps / 2] / ours[reps / 2]
    );
}
