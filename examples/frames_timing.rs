//! Time of normals and principal curvatures alone (diagnostic).
use nbhd::geometry::curvature::{all_principal_curvatures, DensityForm, PrincipalFormula};
use nbhd::geometry::neighbors::neighbor_table;
use nbhd::geometry::normals::local_frames;
use nbhd::shapes::{sample, Torus};
use nbhd::Neighborhood;
use std::time::Instant;

fn main() {
    let s = sample(&Torus::new(1.0, 0.4), 20_000, 1);
    let t = neighbor_table(&s.points, Neighborhood::Knn { k: 15 }, true).unwrap();
    let now = Instant::now();
    let mut f = Vec::new();
    for _ in 0..10 {
        f = local_frames(&s.points, &t).unwrap();
    }
    let frames = now.elapsed().as_secs_f64() / 10.0;
    let now = Instant::now();
    for _ in 0..10 {
        all_principal_curvatures(
            &s.points,
            &t,
            &f,
            DensityForm::AbsLinear,
            PrincipalFormula::Eq225,
        )
        .unwrap();
    }
    let pc = now.elapsed().as_secs_f64() / 10.0;
    println!("20k points, k = 15: frames {frames:.4} s, principal curvatures {pc:.4} s");
}
