//! Mean normal error of covariance normals on clean tori of the thesis' sizes (Fig. 8.2).
//! `cargo run --release --example torus_normals [k]`
use nbhd::geometry::neighbors::neighbor_table;
use nbhd::geometry::normals::local_frames;
use nbhd::shapes::metrics::unsigned_angle_deg;
use nbhd::shapes::{sample, Torus, TORUS_SIZES};
use nbhd::Neighborhood;

fn main() {
    let k: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(15);
    let torus = Torus::new(1.0, 0.4);
    for n in TORUS_SIZES {
        let s = sample(&torus, n, 1);
        let t = neighbor_table(&s.points, Neighborhood::Knn { k }, true).unwrap();
        let f = local_frames(&s.points, &t).unwrap();
        let err: f64 = f
            .iter()
            .zip(&s.normals)
            .map(|(f, &n)| unsigned_angle_deg(f.normal, n))
            .sum::<f64>()
            / n as f64;
        println!("torus {n} points, k = {k}: mean normal error {err:.3}°");
    }
}
