//! The saved-tree loader (src/tree/persist.rs) on arbitrary bytes: the body of the fuzz target
//! `load_tree`, also run on stable by tests/tree_persist.rs over the seeds and regressions.
//!
//! The first byte chooses: bit 0 recomputes both checksums of the rest first (as a crafted file
//! would, so that the fuzzer reaches the structural checks behind them), bit 1 loads as f64
//! instead of f32, bit 2 loads a dynamic tree (src/dynamic/persist.rs) instead of a static one.
//! A load must be refused with a saved-tree error, or give a tree that re-saves to the same
//! fields and payload and answers exactly what brute force answers over the points it holds (a
//! dynamic tree: over its live points, also after an insertion and a removal). A panic, abort
//! or hang is a crash.

use nbhd::dynamic::DynamicKdTree;
use nbhd::tree::HEADER_LEN;
use nbhd::NeighborIndex;
use nbhd::Persist;
use nbhd::{
    BruteForce, KdTree, NbhdError, NeighborSearch, Neighborhood, NonFinitePolicy, PointsView,
    Query, Scalar,
};

/// Recomputes the payload and header CRC-32s of a saved tree (docs/tree-file-format.md).
pub fn reseal(bytes: &mut [u8]) {
    if bytes.len() < HEADER_LEN {
        return;
    }
    let payload = crc32fast::hash(&bytes[HEADER_LEN..]);
    bytes[96..100].copy_from_slice(&payload.to_ne_bytes());
    let header = crc32fast::hash(&bytes[..120]);
    bytes[120..124].copy_from_slice(&header.to_ne_bytes());
}

/// Points up to which a loaded tree is compared with brute force (the table is quadratic).
const BRUTE_MAX: usize = 300;

pub fn load_tree(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let mut bytes = rest.to_vec();
    if mode & 4 == 4 {
        if mode & 1 == 1 {
            reseal_dynamic(&mut bytes);
        }
        if mode & 2 == 0 {
            check_dynamic::<f32>(&bytes);
        } else {
            check_dynamic::<f64>(&bytes);
        }
        return;
    }
    if mode & 1 == 1 {
        reseal(&mut bytes);
    }
    if mode & 2 == 0 {
        check::<f32>(&bytes);
    } else {
        check::<f64>(&bytes);
    }
}

fn check<T: Scalar>(bytes: &[u8]) {
    let loaded = KdTree::<T>::from_bytes(bytes);
    // From a reader: the same verdict, and the same tree.
    let streamed = KdTree::<T>::load(bytes);
    let tree = match (loaded, streamed) {
        (Err(e), r) => {
            assert!(matches!(e, NbhdError::SavedTree(_)), "{e}");
            assert!(!e.to_string().is_empty());
            // A reader ignores what follows the tree; only that may differ.
            if let Ok(t) = r {
                assert!(e.to_string().contains("follow the end"), "{e}");
                drop(t);
            }
            return;
        }
        (Ok(t), Ok(s)) => {
            assert!(t.same_structure(&s));
            t
        }
        (Ok(_), Err(e)) => panic!("loaded from bytes but not from a reader: {e}"),
    };
    // Saved again: the same fields and payload (the writer's version and the CRCs aside).
    let again = tree.to_bytes();
    assert_eq!(again.len(), bytes.len());
    assert_eq!(again[24..96], bytes[24..96]);
    assert_eq!(again[HEADER_LEN..], bytes[HEADER_LEN..]);

    let d = tree.dim();
    let n = tree.source_len();
    // Queries: a few stored points moved a little, and the origin.
    let mut queries = vec![T::ZERO; d];
    for i in (0..n as u32).step_by(n / 5 + 1) {
        if let Some(p) = tree.point(i) {
            queries.extend(p.iter().map(|&c| c + T::from_f64(0.01)));
        }
    }
    let nbhds = [
        Neighborhood::Knn { k: 3 },
        Neighborhood::Radius {
            radius: T::from_f64(0.5),
            sorted: true,
        },
        Neighborhood::KnnRadius {
            k: 2,
            radius: T::from_f64(1.0),
        },
    ];
    let (mut got, mut want) = (Vec::new(), Vec::new());
    if n > BRUTE_MAX || d > 16 {
        for nbhd in nbhds {
            for q in queries.chunks_exact(d) {
                let _ = tree.search(Query::point(q), nbhd, &mut got);
            }
            let _ = tree.search(Query::stored_excluding_self(0), nbhd, &mut got);
        }
        return;
    }
    // The points the tree holds, in caller order, through brute force.
    let mut coords = vec![T::INFINITY; n * d];
    for i in 0..n as u32 {
        if let Some(p) = tree.point(i) {
            coords[i as usize * d..(i as usize + 1) * d].copy_from_slice(p);
        }
    }
    let view = PointsView::from_flat(&coords, d).unwrap();
    let brute = BruteForce::new(&view, NonFinitePolicy::Skip).unwrap();
    for nbhd in nbhds {
        for q in queries.chunks_exact(d) {
            let a = tree.search(Query::point(q), nbhd, &mut got);
            let b = brute.search(Query::point(q), nbhd, &mut want);
            assert_eq!(a, b);
            assert_eq!(got, want);
        }
        let opts = nbhd::TableOptions {
            exclude_self: true,
            threads: 1,
            ..Default::default()
        };
        assert_eq!(
            tree.neighborhoods(nbhd, &opts),
            nbhd::table::neighborhoods_of_all(&brute, nbhd, true)
        );
    }
}

/// Recomputes the payload and header CRC-32s of a saved dynamic tree (its static trees keep
/// theirs).
pub fn reseal_dynamic(bytes: &mut [u8]) {
    if bytes.len() < HEADER_LEN {
        return;
    }
    let payload = crc32fast::hash(&bytes[HEADER_LEN..]);
    bytes[104..108].copy_from_slice(&payload.to_ne_bytes());
    let header = crc32fast::hash(&bytes[..120]);
    bytes[120..124].copy_from_slice(&header.to_ne_bytes());
}

/// Every query kind by every live index and at a few points equals brute force over the live
/// points of `tree` (indices not live given as NaN and skipped).
fn dynamic_exact<T: Scalar>(tree: &DynamicKdTree<T>) {
    let d = tree.dim();
    let n = tree.next_index() as usize;
    let mut coords = vec![T::from_f64(f64::NAN); n * d];
    let mut queries = vec![T::ZERO; d];
    for i in 0..n as u32 {
        if let Some(p) = tree.point(i) {
            coords[i as usize * d..(i as usize + 1) * d].copy_from_slice(p);
            if i % 7 == 0 {
                queries.extend(p.iter().map(|&c| c + T::from_f64(0.01)));
            }
        }
    }
    let brute = BruteForce::new(
        &PointsView::from_flat(&coords, d).unwrap(),
        NonFinitePolicy::Skip,
    );
    let Ok(brute) = brute else {
        // No live point: nothing to find.
        let mut got = Vec::new();
        let r = tree.search(
            Query::point(&queries[..d]),
            Neighborhood::Knn { k: 2 },
            &mut got,
        );
        assert!(r.is_ok() && got.is_empty());
        return;
    };
    let nbhds = [
        Neighborhood::Knn { k: 3 },
        Neighborhood::Radius {
            radius: T::from_f64(0.5),
            sorted: true,
        },
        Neighborhood::KnnRadius {
            k: 2,
            radius: T::from_f64(1.0),
        },
    ];
    let (mut got, mut want) = (Vec::new(), Vec::new());
    for nbhd in nbhds {
        for q in queries.chunks_exact(d) {
            let a = tree.search(Query::point(q), nbhd, &mut got);
            let b = brute.search(Query::point(q), nbhd, &mut want);
            assert_eq!(a, b);
            assert_eq!(got, want);
        }
        for i in (0..n as u32).filter(|&i| tree.is_live(i)) {
            tree.search(Query::stored_excluding_self(i), nbhd, &mut got)
                .unwrap();
            brute
                .search(Query::stored_excluding_self(i), nbhd, &mut want)
                .unwrap();
            assert_eq!(got, want);
        }
    }
}

fn check_dynamic<T: Scalar>(bytes: &[u8]) {
    let loaded = DynamicKdTree::<T>::from_bytes(bytes);
    let streamed = DynamicKdTree::<T>::load(bytes);
    let mut tree = match (loaded, streamed) {
        (Err(e), r) => {
            assert!(matches!(e, NbhdError::SavedTree(_)), "{e}");
            assert!(!e.to_string().is_empty());
            if let Ok(t) = r {
                assert!(e.to_string().contains("follow the end"), "{e}");
                drop(t);
            }
            return;
        }
        (Ok(t), Ok(s)) => {
            assert_eq!(t.stats(), s.stats());
            t
        }
        (Ok(_), Err(e)) => panic!("loaded from bytes but not from a reader: {e}"),
    };
    let again = tree.to_bytes();
    assert_eq!(again.len(), bytes.len());
    assert_eq!(again[24..104], bytes[24..104]);
    if tree.next_index() > BRUTE_MAX as u32 || tree.dim() > 16 {
        return;
    }
    dynamic_exact(&tree);
    // It grows and shrinks: a batch near the first live point, then a removal.
    let d = tree.dim();
    let near: Vec<T> = (0..3 * d).map(|j| T::from_f64(0.1 * j as f64)).collect();
    if tree.insert_flat(&near).is_ok() {
        let first_live = (0..tree.next_index()).find(|&i| tree.is_live(i));
        if let Some(i) = first_live {
            tree.remove(&[i]).unwrap();
        }
        dynamic_exact(&tree);
    }
}
