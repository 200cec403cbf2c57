//! Time of the normals and of their orientation on a torus of 1M points (issue 13 item 10: the
//! orientation may take no more time than the normals themselves). Prints the neighbour table,
//! the normals, and each orientation (propagation over the neighbour graph, toward a
//! viewpoint), and checks that propagation orients every normal outward.
//! `cargo run --release --example orient_timing [points]`
use nbhd::geometry::neighbors::neighbor_table;
use nbhd::geometry::normals::{local_frames, orient, Orientation};
use nbhd::shapes::{sample, Shape, Torus};
use nbhd::Neighborhood;
use std::time::Instant;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(1_000_000, |a| a.parse().expect("a number of points"));
    let torus = Torus::new(1.0, 0.4);
    let s = sample(&torus, n, 1);
    let now = Instant::now();
    let t = neighbor_table(&s.points, Neighborhood::Knn { k: 15 }, true).unwrap();
    let table = now.elapsed().as_secs_f64();
    let now = Instant::now();
    let frames = local_frames(&s.points, &t).unwrap();
    let normals = now.elapsed().as_secs_f64();
    let mut f = frames.clone();
    let now = Instant::now();
    orient(&s.points, &t, &mut f, Orientation::Propagate).unwrap();
    let propagate = now.elapsed().as_secs_f64();
    let outward = f
        .iter()
        .zip(&s.points)
        .filter(|(f, &p)| f.normal.dot(torus.closest(p).normal) > 0.0)
        .count();
    let mut g = frames.clone();
    let now = Instant::now();
    orient(
        &s.points,
        &t,
        &mut g,
        Orientation::TowardViewpoint(glam::DVec3::new(0.0, 0.0, 10.0)),
    )
    .unwrap();
    let viewpoint = now.elapsed().as_secs_f64();
    println!(
        "{n} points, k = 15: table {table:.3} s, normals {normals:.3} s, propagate \
         {propagate:.3} s ({outward} of {n} outward), viewpoint {viewpoint:.4} s \
         ({} threads)",
        rayon::current_num_threads()
    );
}
