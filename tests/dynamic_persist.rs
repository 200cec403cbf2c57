//! Saved dynamic trees (src/dynamic/persist.rs, docs/tree-file-format.md "Dynamic trees"): a
//! loaded forest answers every query exactly as the saved one, bit for bit, grows and shrinks
//! the same way afterwards and saves to the same bytes, for f32 and f64, with duplicates,
//! skipped non-finite points and removals; and bad input is refused with the error that names
//! it: a static tree (and a dynamic tree given to the static loader), another scalar type,
//! dimension, format version or byte order, truncation, trailing bytes, flipped bits, and
//! changes with recomputed checksums (a crafted file), whose loaded forest must then still
//! answer exactly what brute force over its live points answers.

mod common;

use common::{points, Kind, Rng};
use nbhd::dynamic::{DynamicKdTree, SavedDynamicInfo};
use nbhd::error::SavedTreeError;
use nbhd::tree::{LoadOptions, HEADER_LEN};
use nbhd::NeighborIndex;
use nbhd::Persist;
use nbhd::{
    BruteForce, BuildOptions, KdTree, NbhdError, NeighborSearch, Neighborhood, NonFinitePolicy,
    PointsView, Query, Scalar, TableOptions,
};

fn nbhds<T: Scalar>() -> Vec<Neighborhood<T>> {
    vec![
        Neighborhood::Knn { k: 1 },
        Neighborhood::Knn { k: 7 },
        Neighborhood::Radius {
            radius: T::from_f64(0.3),
            sorted: true,
        },
        Neighborhood::KnnRadius {
            k: 5,
            radius: T::from_f64(0.25),
        },
    ]
}

/// A forest grown by random batches (duplicates, every 13th point NaN and skipped) and
/// removals.
fn grown<T: Scalar>(d: usize, seed: u64, steps: usize) -> DynamicKdTree<T> {
    let options = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        leaf_size: 4,
        ..BuildOptions::default()
    };
    let mut tree = DynamicKdTree::<T>::new(d, &options).unwrap();
    let mut rng = Rng::new(seed);
    for step in 0..steps {
        let n = 1 + rng.below(60);
        let mut c = points(Kind::DuplicateHeavy, n, d, seed * 100 + step as u64);
        for i in (3..n).step_by(13) {
            c[i * d] = f64::NAN;
        }
        let c: Vec<T> = c.into_iter().map(T::from_f64).collect();
        tree.insert_flat(&c).unwrap();
        let live: Vec<u32> = (0..tree.next_index())
            .filter(|&i| tree.is_live(i))
            .collect();
        let mut gone: Vec<u32> = live.iter().copied().filter(|_| rng.below(4) == 0).collect();
        gone.truncate(live.len().saturating_sub(5));
        tree.remove(&gone).unwrap();
    }
    tree
}

/// Every query kind by every stored index and at free points, and both tables (1 and 2
/// threads), are identical in `a` and `b` (bitwise: `Neighbor` compares `sq_dist` exactly).
fn same_answers<T: Scalar>(a: &DynamicKdTree<T>, b: &DynamicKdTree<T>, rng: &mut Rng) {
    let d = a.dim();
    assert_eq!(a.stats(), b.stats());
    assert_eq!(a.next_index(), b.next_index());
    let (mut ra, mut rb) = (Vec::new(), Vec::new());
    let free: Vec<T> = (0..5 * d)
        .map(|_| T::from_f64(rng.uniform(-0.2, 1.2)))
        .collect();
    for nb in nbhds::<T>() {
        for i in 0..a.next_index() {
            for exclude_self in [false, true] {
                let q = Query::Stored {
                    index: i,
                    exclude_self,
                };
                assert_eq!(a.search(q, nb, &mut ra), b.search(q, nb, &mut rb));
                assert_eq!(ra, rb);
            }
        }
        for q in free.chunks_exact(d) {
            a.search(Query::point(q), nb, &mut ra).unwrap();
            b.search(Query::point(q), nb, &mut rb).unwrap();
            assert_eq!(ra, rb);
        }
        for threads in [1, 2] {
            let o = TableOptions {
                threads,
                ..TableOptions::default()
            };
            assert_eq!(a.neighborhoods(nb, &o), b.neighborhoods(nb, &o));
            let qv = PointsView::from_flat(&free, d).unwrap();
            assert_eq!(
                a.neighborhoods_of(&qv, nb, &o),
                b.neighborhoods_of(&qv, nb, &o)
            );
        }
    }
}

fn round_trip<T: Scalar>(d: usize, seed: u64) {
    let mut rng = Rng::new(seed);
    let mut a = grown::<T>(d, seed, 12);
    let bytes = a.to_bytes();
    assert_eq!(bytes.len(), a.saved_len());
    let mut b = DynamicKdTree::<T>::from_bytes(&bytes).unwrap();
    same_answers(&a, &b, &mut rng);
    assert_eq!(
        b.to_bytes(),
        bytes,
        "a loaded forest saves to the same bytes"
    );
    // From a reader, leaving what follows unread; and `save` writes the same bytes.
    let mut written = Vec::new();
    a.save(&mut written).unwrap();
    assert_eq!(written, bytes);
    written.extend_from_slice(b"tail");
    let mut r = &written[..];
    let c = DynamicKdTree::<T>::load(&mut r).unwrap();
    assert_eq!(r, b"tail");
    same_answers(&a, &c, &mut rng);
    // The loaded forest grows and shrinks as the saved one does.
    for step in 0..4 {
        let n = 10 + 20 * step;
        let p: Vec<T> = points(Kind::Random, n, d, seed + 7 + step as u64)
            .into_iter()
            .map(T::from_f64)
            .collect();
        assert_eq!(a.insert_flat(&p).unwrap(), b.insert_flat(&p).unwrap());
        let gone: Vec<u32> = (0..a.next_index())
            .filter(|&i| a.is_live(i) && rng.below(3) == 0)
            .collect();
        a.remove(&gone).unwrap();
        b.remove(&gone).unwrap();
        same_answers(&a, &b, &mut rng);
        assert_eq!(a.to_bytes(), b.to_bytes());
    }
}

#[test]
fn round_trip_f32_and_f64() {
    round_trip::<f32>(3, 1);
    round_trip::<f64>(3, 2);
    round_trip::<f64>(1, 3);
    round_trip::<f32>(5, 4);
}

#[test]
fn empty_and_file_round_trip() {
    let options = BuildOptions::default();
    let empty = DynamicKdTree::<f64>::new(2, &options).unwrap();
    let back = DynamicKdTree::<f64>::from_bytes(&empty.to_bytes()).unwrap();
    assert_eq!(back.stats(), empty.stats());
    assert_eq!(back.dim(), 2);
    // Everything inserted then removed: indices stay given, nothing is live.
    let mut t = DynamicKdTree::<f32>::new(2, &options).unwrap();
    t.insert_flat(&[0.0, 1.0, 2.0, 3.0]).unwrap();
    t.remove(&[0, 1]).unwrap();
    let back = DynamicKdTree::<f32>::from_bytes(&t.to_bytes()).unwrap();
    assert_eq!(back.next_index(), 2);
    assert_eq!(
        back.knn(Query::stored(1), 1, &mut Vec::new()),
        Err(NbhdError::RemovedPoint { index: 1 })
    );
    let a = grown::<f32>(3, 9, 6);
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("nbhd-dynamic-{}.nbhdfrst", std::process::id()));
    a.save_file(&path).unwrap();
    let b = DynamicKdTree::<f32>::load_file(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    same_answers(&a, &b, &mut Rng::new(5));
    let e = DynamicKdTree::<f32>::load_file(&path).unwrap_err();
    assert!(matches!(e, NbhdError::Io { .. }), "{e}");
}

fn saved_error<T: Scalar>(bytes: &[u8]) -> SavedTreeError {
    match DynamicKdTree::<T>::from_bytes(bytes) {
        Err(NbhdError::SavedTree(e)) => e,
        Err(e) => panic!("not a saved-tree error: {e}"),
        Ok(_) => panic!("loaded"),
    }
}

#[test]
fn other_kinds_types_and_versions_are_named() {
    let t = grown::<f32>(3, 11, 4);
    let bytes = t.to_bytes();
    // A dynamic tree is not a static one, and the reverse; both loaders say so.
    let e = match KdTree::<f32>::from_bytes(&bytes) {
        Err(NbhdError::SavedTree(e)) => e,
        other => panic!("{other:?}"),
    };
    assert!(matches!(e, SavedTreeError::OtherKind { .. }), "{e}");
    assert!(e.to_string().contains("a dynamic tree (NBHDFRST)"), "{e}");
    let c: Vec<f32> = (0..30).map(|i| i as f32).collect();
    let fixed = KdTree::<f32>::build(
        &PointsView::from_flat(&c, 3).unwrap(),
        &BuildOptions::default(),
    )
    .unwrap();
    let e = saved_error::<f32>(&fixed.to_bytes());
    assert!(matches!(e, SavedTreeError::OtherKind { .. }), "{e}");
    assert!(e.to_string().contains("a static tree (NBHDTREE)"), "{e}");
    let e = saved_error::<f32>(b"PLY\nformat ascii 1.0\n");
    assert!(matches!(e, SavedTreeError::NotATree { .. }), "{e}");
    assert!(e.to_string().contains("NBHDFRST"), "{e}");
    // Scalar type and dimension.
    let e = saved_error::<f64>(&bytes);
    assert_eq!(
        e,
        SavedTreeError::ScalarType {
            file: "f32",
            expected: "f64"
        }
    );
    assert_eq!(
        DynamicKdTree::<f32>::from_bytes_with(&bytes, &LoadOptions { dim: Some(2) }).err(),
        Some(NbhdError::SavedTree(SavedTreeError::Dimension {
            file: 3,
            expected: 2
        }))
    );
    let info = SavedDynamicInfo::from_bytes(&bytes).unwrap();
    assert_eq!(
        (info.dim, info.live, info.trees),
        (3, t.len(), t.stats().trees.len())
    );
    // Another format version, named with the version that wrote it.
    let mut v2 = bytes.clone();
    v2[12..16].copy_from_slice(&2u32.to_ne_bytes());
    let e = saved_error::<f32>(&v2);
    assert!(
        matches!(
            e,
            SavedTreeError::FormatVersion {
                file: 2,
                supported: 1,
                ..
            }
        ),
        "{e}"
    );
    // The other byte order.
    let mut swapped = bytes.clone();
    swapped[8..12].reverse();
    assert!(matches!(
        saved_error::<f32>(&swapped),
        SavedTreeError::ByteOrder { .. }
    ));
    // Trailing bytes.
    let mut long = bytes.clone();
    long.push(0);
    assert!(
        matches!(saved_error::<f32>(&long), SavedTreeError::Invalid(m) if m.contains("1 bytes follow"))
    );
}

#[test]
fn every_truncation_and_flipped_bit_is_refused() {
    let t = grown::<f32>(2, 21, 3);
    let bytes = t.to_bytes();
    for len in 0..bytes.len() {
        let e = saved_error::<f32>(&bytes[..len]);
        // (a prefix of the magic is a truncated file, not another kind)
        assert!(
            matches!(e, SavedTreeError::Truncated { .. }),
            "length {len}: {e}"
        );
        // From a reader too.
        assert!(DynamicKdTree::<f32>::load(&bytes[..len]).is_err());
    }
    for at in 0..bytes.len() {
        for b in 0..8 {
            let mut x = bytes.clone();
            x[at] ^= 1 << b;
            let e = saved_error::<f32>(&x);
            let ok = match at {
                0..=7 => matches!(e, SavedTreeError::NotATree { .. }),
                12..=15 => matches!(e, SavedTreeError::FormatVersion { .. }),
                120..=123 | 8..=11 | 16..=119 => {
                    matches!(e, SavedTreeError::Checksum { part: "header", .. })
                }
                124..=127 => matches!(e, SavedTreeError::Invalid(_)),
                _ => matches!(
                    e,
                    SavedTreeError::Checksum {
                        part: "payload",
                        ..
                    }
                ),
            };
            assert!(ok, "byte {at} bit {b}: {e}");
        }
    }
}

/// Recomputes the forest's checksums after a change, as a crafted file would.
fn reseal(bytes: &mut [u8]) {
    let payload = crc32fast::hash(&bytes[HEADER_LEN..]);
    bytes[104..108].copy_from_slice(&payload.to_ne_bytes());
    let header = crc32fast::hash(&bytes[..120]);
    bytes[120..124].copy_from_slice(&header.to_ne_bytes());
}

/// A crafted file (changes with the forest's checksums recomputed) is refused, or the loaded
/// forest answers exactly what brute force over its own live points answers.
#[test]
fn crafted_files_are_refused_or_exact() {
    let t = grown::<f64>(2, 31, 5);
    let bytes = t.to_bytes();
    let mut rng = Rng::new(77);
    let (mut loaded, mut refused) = (0, 0);
    let mut out = Vec::new();
    let mut want = Vec::new();
    for round in 0..3000 {
        let mut x = bytes.clone();
        let changes = 1 + rng.below(3);
        for _ in 0..changes {
            // Mostly in the header's fields and the forest's own sections (before the trees).
            let at = if round % 2 == 0 {
                32 + rng.below(72)
            } else {
                HEADER_LEN + rng.below(x.len() - HEADER_LEN)
            };
            x[at] = match rng.below(3) {
                0 => x[at] ^ (1 << rng.below(8)),
                1 => 0,
                _ => rng.below(256) as u8,
            };
        }
        reseal(&mut x);
        let f = match DynamicKdTree::<f64>::from_bytes(&x) {
            Ok(f) => f,
            Err(NbhdError::SavedTree(e)) => {
                assert!(!e.to_string().is_empty());
                refused += 1;
                continue;
            }
            Err(e) => panic!("round {round}: not a saved-tree error: {e}"),
        };
        loaded += 1;
        let d = f.dim();
        let n = f.next_index() as usize;
        let mut masked = vec![f64::NAN; n * d];
        for i in 0..n as u32 {
            if let Some(p) = f.point(i) {
                masked[i as usize * d..][..d].copy_from_slice(p);
            }
        }
        let brute = BruteForce::new(
            &PointsView::from_flat(&masked, d).unwrap(),
            NonFinitePolicy::Skip,
        )
        .unwrap();
        for nb in nbhds::<f64>() {
            for i in (0..n as u32).filter(|&i| f.is_live(i)) {
                f.search(Query::stored(i), nb, &mut out).unwrap();
                brute.search(Query::stored(i), nb, &mut want).unwrap();
                assert_eq!(out, want, "round {round}, index {i}");
            }
        }
    }
    assert!(refused > 0);
    // Changes that leave a valid forest (e.g. the growth factor or the nbhd version) load.
    assert!(loaded > 0, "no change was accepted ({refused} refused)");
}

/// A file is untrusted input: the thread count it states is not obeyed (a file saying 1024
/// made every later insertion build on 1024 threads), the loaded tree builds on the default
/// until `set_threads`; and a dimension whose point would not fit in memory is refused (an
/// empty saved tree loaded with any), as `DynamicKdTree::new` refuses it.
#[test]
fn saved_threads_are_not_obeyed_and_huge_dimensions_are_refused() {
    let options = BuildOptions {
        threads: 2,
        ..BuildOptions::default()
    };
    let mut t = DynamicKdTree::<f32>::new(3, &options).unwrap();
    t.insert_flat(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
    let mut bytes = t.to_bytes();
    assert_eq!(u64::from_ne_bytes(bytes[88..96].try_into().unwrap()), 2);
    bytes[88..96].copy_from_slice(&1024u64.to_ne_bytes());
    reseal(&mut bytes);
    assert_eq!(
        SavedDynamicInfo::from_bytes(&bytes)
            .unwrap()
            .options
            .threads,
        1024
    );
    let mut back = DynamicKdTree::<f32>::from_bytes(&bytes).unwrap();
    assert_eq!(
        back.options().threads,
        0,
        "the file's thread count was obeyed"
    );
    back.set_threads(1).unwrap();
    assert_eq!(back.options().threads, 1);
    back.insert_flat(&[6.0, 7.0, 8.0]).unwrap();
    assert!(matches!(
        back.set_threads(nbhd::MAX_THREADS + 1),
        Err(NbhdError::InvalidOption {
            name: "threads",
            ..
        })
    ));
    assert_eq!(back.options().threads, 1);

    for (scalar_size, dim) in [
        (4, usize::MAX),
        (4, usize::MAX / 4 + 1),
        (8, isize::MAX as usize / 8 + 1),
    ] {
        let e = if scalar_size == 4 {
            DynamicKdTree::<f32>::new(dim, &BuildOptions::default()).unwrap_err()
        } else {
            DynamicKdTree::<f64>::new(dim, &BuildOptions::default()).unwrap_err()
        };
        assert!(
            matches!(e, NbhdError::SizeOverflow { .. }),
            "dim {dim}: {e}"
        );
    }
    let empty = DynamicKdTree::<f64>::new(2, &BuildOptions::default()).unwrap();
    for dim in [u64::MAX, isize::MAX as u64 / 8 + 1] {
        let mut bytes = empty.to_bytes();
        bytes[32..40].copy_from_slice(&dim.to_ne_bytes());
        reseal(&mut bytes);
        let e = saved_error::<f64>(&bytes);
        assert!(e.to_string().contains(&format!("dimension {dim}")), "{e}");
    }
}
