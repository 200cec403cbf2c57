//! Time of the smoothing steps alone (total minus a zero-step run that only searches), each run
//! repeated and summarised by its median and minimum (the machine may be shared).
//! `cargo run --release --example smooth_timing [points] [steps] [repeats]`
use nbhd::geometry::neighbors::mean_spacing;
use nbhd::shapes::{add_noise, sample, NoiseKind, Torus};
use nbhd::smooth::{smooth, SmoothOptions};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let steps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let repeats: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(5).max(1);
    let s = sample(&Torus::new(1.0, 0.4), n, 1);
    let h = mean_spacing(&s.points).unwrap();
    let p = add_noise(&s, 1.0, h, NoiseKind::Gaussian, 2).unwrap();
    // (median, minimum) over the repeats
    let time = |o: SmoothOptions| {
        let mut t: Vec<f64> = (0..repeats)
            .map(|_| {
                let t = Instant::now();
                smooth(&p, &o).unwrap();
                t.elapsed().as_secs_f64()
            })
            .collect();
        t.sort_by(f64::total_cmp);
        (t[t.len() / 2], t[0])
    };
    let base = SmoothOptions {
        outputs: false,
        ..SmoothOptions::default()
    };
    let search = time(SmoothOptions { steps: 0, ..base });
    let aniso = time(SmoothOptions { steps, ..base });
    let iso = time(SmoothOptions {
        steps,
        ..SmoothOptions {
            outputs: false,
            ..SmoothOptions::isotropic()
        }
    });
    println!(
        "{n} points, median (min) of {repeats}: search {:.3} ({:.3}) s; \
         {steps} anisotropic steps {:.3} ({:.3}) s, isotropic {:.3} ({:.3}) s; \
         anisotropic total {:.3} ({:.3}) s",
        search.0,
        search.1,
        aniso.0 - search.0,
        aniso.1 - search.1,
        iso.0 - search.0,
        iso.1 - search.1,
        aniso.0,
        aniso.1
    );
}
