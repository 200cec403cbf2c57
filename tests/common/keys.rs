//! Keys computed from the definitions, for the brute forces the tests compare with: each
//! axis difference at its nearest periodic image (`min(t, L − t)`, the query wrapped into
//! `[0, L)`; an open axis has size +∞, so `t` itself), folded over the axes in order as the
//! library folds them.

use nbhd::{Metric, Scalar};

/// Wraps `x` into `[0, L)` (nothing on an open axis), in `T` as the tree does.
pub fn wrap<T: Scalar>(x: T, l: T) -> T {
    if !l.is_finite() {
        return x;
    }
    let r = x % l;
    let r = if r < T::ZERO { r + l } else { r };
    if r < l {
        r
    } else {
        T::ZERO
    }
}

/// The key from `q` to `p` under `metric` with every axis at its nearest image.
pub fn key<T: Scalar>(metric: Metric, q: &[T], p: &[T], sizes: &[T]) -> T {
    let mut s = T::ZERO;
    for j in 0..q.len() {
        let t = (wrap(q[j], sizes[j]) - p[j]).abs();
        let t = t.min_of(sizes[j] - t);
        s = match metric {
            Metric::Euclidean => s + t * t,
            Metric::Manhattan => s + t,
            Metric::Chebyshev => s.max_of(t),
            Metric::Minkowski(p) => s + t.powf(T::from_f64(p)),
        };
    }
    s
}
