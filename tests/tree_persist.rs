//! Saved trees (src/tree/persist.rs, docs/tree-file-format.md): a loaded tree answers every
//! query exactly as the saved one, bit for bit, for every pivot policy and median algorithm,
//! f32 and f64, in 1, 3 and 7 dimensions, with duplicates and skipped non-finite points; and
//! every kind of bad input is refused with the error that names it: another magic, byte order,
//! format version, scalar type or dimension, truncation, trailing bytes, flipped bits, and
//! payloads whose checksums were recomputed after a change (a crafted file), whose loaded tree
//! must then still answer exactly what brute force answers.

mod common;

use common::{points, to_f32, Kind, Rng};
use nbhd::error::SavedTreeError;
use nbhd::tree::{LoadOptions, SavedTreeInfo, HEADER_LEN};
use nbhd::NeighborIndex;
use nbhd::Persist;
use nbhd::{
    BruteForce, BuildOptions, KdTree, MedianAlgorithm, NbhdError, NeighborSearch, Neighborhood,
    NonFinitePolicy, PivotPolicy, PointsView, Query, Scalar, TableOptions,
};

/// Duplicate-heavy points with every 17th point made non-finite (skipped at build time).
fn cloud(n: usize, d: usize, seed: u64) -> Vec<f64> {
    let mut c = points(Kind::DuplicateHeavy, n, d, seed);
    for i in (5..n).step_by(17) {
        c[i * d + (i % d)] = if i % 2 == 0 { f64::NAN } else { f64::INFINITY };
    }
    c
}

fn build<T: Scalar>(c: &[T], d: usize, options: BuildOptions) -> KdTree<T> {
    KdTree::build(&PointsView::from_flat(c, d).unwrap(), &options).unwrap()
}

fn saved_error<T: Scalar>(bytes: &[u8]) -> SavedTreeError {
    match KdTree::<T>::from_bytes(bytes) {
        Err(NbhdError::SavedTree(e)) => e,
        Err(e) => panic!("not a saved-tree error: {e}"),
        Ok(_) => panic!("loaded"),
    }
}

/// Recomputes both checksums after a change, as a crafted file would.
fn reseal(bytes: &mut [u8]) {
    let payload = crc32fast::hash(&bytes[HEADER_LEN..]);
    bytes[96..100].copy_from_slice(&payload.to_ne_bytes());
    let header = crc32fast::hash(&bytes[..120]);
    bytes[120..124].copy_from_slice(&header.to_ne_bytes());
}

/// Every single query and table of `a` and `b` over `queries` (and every stored index) is
/// identical; `coord` is a radius in the points' scale.
fn same_answers<T: Scalar>(a: &KdTree<T>, b: &KdTree<T>, queries: &[T], what: &str) {
    let d = a.dim();
    let (mut ra, mut rb) = (Vec::new(), Vec::new());
    let nbhds = [
        Neighborhood::Knn { k: 1 },
        Neighborhood::Knn { k: 9 },
        Neighborhood::Knn { k: 1000 },
        Neighborhood::Radius {
            radius: T::from_f64(0.3),
            sorted: true,
        },
        Neighborhood::KnnRadius {
            k: 5,
            radius: T::from_f64(0.5),
        },
    ];
    for nbhd in nbhds {
        for q in queries.chunks_exact(d) {
            let x = a.search(Query::point(q), nbhd, &mut ra);
            let y = b.search(Query::point(q), nbhd, &mut rb);
            assert_eq!(x, y, "{what}");
            assert_eq!(ra, rb, "{what} {nbhd:?} at {q:?}");
        }
        for i in 0..a.source_len() as u32 {
            for query in [Query::stored(i), Query::stored_excluding_self(i)] {
                let x = a.search(query, nbhd, &mut ra);
                let y = b.search(query, nbhd, &mut rb);
                assert_eq!(x, y, "{what} stored {i}");
                assert_eq!(ra, rb, "{what} {nbhd:?} stored {i}");
            }
        }
        let opts = TableOptions::default();
        assert_eq!(
            a.neighborhoods(nbhd, &opts),
            b.neighborhoods(nbhd, &opts),
            "{what} table {nbhd:?}"
        );
        let view = PointsView::from_flat(queries, d).unwrap();
        assert_eq!(
            a.neighborhoods_of(&view, nbhd, &opts),
            b.neighborhoods_of(&view, nbhd, &opts),
            "{what} table of queries {nbhd:?}"
        );
    }
}

fn round_trip<T: Scalar>(convert: fn(&[f64]) -> Vec<T>) {
    for d in [1, 3, 7] {
        let c = convert(&cloud(400, d, 11 + d as u64));
        let queries = convert(&points(Kind::Random, 24, d, 5));
        for pivot in PivotPolicy::ALL {
            for median in MedianAlgorithm::ALL {
                for leaf_size in [1, 12] {
                    let options = BuildOptions {
                        pivot,
                        median,
                        leaf_size,
                        non_finite: NonFinitePolicy::Skip,
                        threads: 1,
                    };
                    let what = format!("{:?} d={d} {pivot:?} {median:?} leaf {leaf_size}", T::TYPE);
                    let tree = build(&c, d, options);
                    let bytes = tree.to_bytes();
                    assert_eq!(bytes.len(), tree.saved_len(), "{what}");
                    let mut written = Vec::new();
                    tree.save(&mut written).unwrap();
                    assert_eq!(written, bytes, "{what}: save and to_bytes agree");

                    let loaded = KdTree::<T>::from_bytes(&bytes).unwrap();
                    assert!(loaded.same_structure(&tree), "{what}");
                    assert_eq!(loaded.stats(), tree.stats(), "{what}");
                    assert_eq!(loaded.options(), tree.options(), "{what}");
                    assert_eq!(loaded.source_len(), tree.source_len(), "{what}");
                    assert_eq!(loaded.tree_order(), tree.tree_order(), "{what}");
                    // Saved again, the loaded tree gives the same bytes.
                    assert_eq!(loaded.to_bytes(), bytes, "{what}");
                    // From a reader, which must stop at the tree's end.
                    let mut stream = bytes.clone();
                    stream.extend_from_slice(b"after");
                    let mut r = std::io::Cursor::new(&stream);
                    let streamed = KdTree::<T>::load(&mut r).unwrap();
                    assert!(streamed.same_structure(&tree), "{what}");
                    assert_eq!(r.position() as usize, bytes.len(), "{what}");

                    let info = SavedTreeInfo::from_bytes(&bytes).unwrap();
                    assert_eq!(info.scalar, T::TYPE);
                    assert_eq!((info.dim, info.points), (d, tree.len()));
                    assert_eq!(info.source_len, 400);
                    assert_eq!(info.options, options);
                    assert_eq!(info.total_len, bytes.len() as u64);

                    // The full comparison on a spread of the combinations (all 20 build the
                    // same structure per policy, checked above).
                    if median == MedianAlgorithm::FloydRivest
                        || (pivot == PivotPolicy::CyclicMedian && leaf_size == 1)
                    {
                        same_answers(&tree, &loaded, &queries, &what);
                    }
                }
            }
        }
    }
}

#[test]
fn loaded_f32_trees_answer_every_query_identically() {
    round_trip::<f32>(to_f32);
}

#[test]
fn loaded_f64_trees_answer_every_query_identically() {
    round_trip::<f64>(|v| v.to_vec());
}

#[test]
fn files_round_trip_and_missing_files_name_the_path() {
    let c = points(Kind::Clustered, 3000, 3, 2);
    let tree = build(&c, 3, BuildOptions::default());
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("nbhd-persist-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("clustered.nbhdtree");
    tree.save_file(&path).unwrap();
    let loaded = KdTree::<f64>::load_file(&path).unwrap();
    assert!(loaded.same_structure(&tree));
    assert_eq!(std::fs::read(&path).unwrap(), tree.to_bytes());
    let missing = dir.join("missing.nbhdtree");
    let e = KdTree::<f64>::load_file(&missing).unwrap_err();
    assert!(matches!(
        e,
        NbhdError::Io {
            kind: std::io::ErrorKind::NotFound,
            ..
        }
    ));
    assert!(e.to_string().contains("missing.nbhdtree"), "{e}");
    let e = tree
        .save_file(dir.join("no-such-dir/x.nbhdtree"))
        .unwrap_err();
    assert!(e.to_string().contains("no-such-dir"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn small_tree() -> KdTree<f32> {
    let c = to_f32(&cloud(60, 3, 9));
    build(
        &c,
        3,
        BuildOptions {
            leaf_size: 2,
            non_finite: NonFinitePolicy::Skip,
            ..BuildOptions::default()
        },
    )
}

#[test]
fn mismatches_are_refused_naming_what_differs() {
    let tree = small_tree();
    let bytes = tree.to_bytes();

    // Another scalar type, and another dimension when one is asked for.
    let e = saved_error::<f64>(&bytes);
    assert_eq!(
        e,
        SavedTreeError::ScalarType {
            file: "f32",
            expected: "f64"
        }
    );
    assert!(e.to_string().contains("f32") && e.to_string().contains("f64"));
    let e = KdTree::<f32>::from_bytes_with(&bytes, &LoadOptions { dim: Some(2) }).unwrap_err();
    assert_eq!(
        e,
        NbhdError::SavedTree(SavedTreeError::Dimension {
            file: 3,
            expected: 2
        })
    );
    assert!(KdTree::<f32>::from_bytes_with(&bytes, &LoadOptions { dim: Some(3) }).is_ok());

    // Not a tree at all.
    let e = saved_error::<f32>(b"ply\nformat ascii 1.0\n");
    assert!(matches!(e, SavedTreeError::NotATree { .. }), "{e}");
    assert!(e.to_string().contains("ply"), "{e}");

    // The other byte order: the byte-order mark reversed.
    let mut other = bytes.clone();
    other[8..12].reverse();
    let e = saved_error::<f32>(&other);
    assert!(matches!(e, SavedTreeError::ByteOrder { .. }), "{e}");
    assert!(e.to_string().contains("big-endian"), "{e}");

    // Another format version, written by another library version.
    let mut newer = bytes.clone();
    newer[12..16].copy_from_slice(&2u32.to_ne_bytes());
    newer[20..24].copy_from_slice(&1_004_002u32.to_ne_bytes());
    let e = saved_error::<f32>(&newer);
    assert_eq!(
        e,
        SavedTreeError::FormatVersion {
            file: 2,
            supported: 1,
            written_by: "1.4.2".into()
        }
    );
    assert!(e.to_string().contains("format version 2"), "{e}");

    // Trailing bytes.
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(matches!(
        saved_error::<f32>(&longer),
        SavedTreeError::Invalid(m) if m.contains("1 bytes follow")
    ));
}

#[test]
fn every_truncation_is_refused() {
    let bytes = small_tree().to_bytes();
    for len in 0..bytes.len() {
        let e = saved_error::<f32>(&bytes[..len]);
        assert!(
            matches!(e, SavedTreeError::Truncated { needed, available }
                if available == len as u64 && needed == if len < HEADER_LEN { 128 } else { bytes.len() as u64 }),
            "{len}: {e}"
        );
        let e = KdTree::<f32>::load(&bytes[..len]).unwrap_err();
        assert!(
            matches!(e, NbhdError::SavedTree(SavedTreeError::Truncated { .. })),
            "{len}: {e}"
        );
    }
}

#[test]
fn every_flipped_bit_is_refused() {
    let bytes = small_tree().to_bytes();
    for bit in 0..bytes.len() * 8 {
        let mut b = bytes.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        // CRC-32 detects every single-bit error; the magic, byte order and version are
        // reported as what they are.
        let e = saved_error::<f32>(&b);
        let expected = match bit / 8 {
            0..=7 => matches!(e, SavedTreeError::NotATree { .. }),
            8..=11 => matches!(e, SavedTreeError::Checksum { part: "header", .. }),
            12..=15 => matches!(e, SavedTreeError::FormatVersion { .. }),
            16..=123 => matches!(e, SavedTreeError::Checksum { part: "header", .. }),
            124..=127 => matches!(e, SavedTreeError::Invalid(_)),
            _ => matches!(
                e,
                SavedTreeError::Checksum {
                    part: "payload",
                    ..
                }
            ),
        };
        assert!(expected, "bit {bit}: {e}");
    }
}

/// Writes `v` at `at` in a copy of `bytes`, reseals it and loads it.
fn crafted(bytes: &[u8], at: usize, v: &[u8]) -> Result<KdTree<f32>, NbhdError> {
    let mut b = bytes.to_vec();
    b[at..at + v.len()].copy_from_slice(v);
    reseal(&mut b);
    KdTree::<f32>::from_bytes(&b)
}

fn invalid_message(r: Result<KdTree<f32>, NbhdError>) -> String {
    match r {
        Err(NbhdError::SavedTree(SavedTreeError::Invalid(m))) => m,
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("loaded"),
    }
}

#[test]
fn crafted_structures_are_refused_with_the_reason() {
    let tree = small_tree();
    let bytes = tree.to_bytes();
    let info = SavedTreeInfo::from_bytes(&bytes).unwrap();
    let (n, d) = (info.points, info.dim);
    let coords = HEADER_LEN;
    let ids = coords + (n * d * 4).next_multiple_of(8);
    let nodes = ids + (n * 4).next_multiple_of(8);
    let node = |i: usize| nodes + 16 * i;
    let u32s = |v: u32| v.to_ne_bytes();

    // Header fields out of range.
    let m = invalid_message(crafted(
        &bytes,
        40,
        &(u64::from(u32::MAX) + 1).to_ne_bytes(),
    ));
    assert!(m.contains("points"), "{m}");
    let m = invalid_message(crafted(&bytes, 32, &0u64.to_ne_bytes()));
    assert!(m.contains("dimension 0"), "{m}");
    let m = invalid_message(crafted(&bytes, 32, &(1u64 << 62).to_ne_bytes()));
    assert!(m.contains("overflows"), "{m}");
    let m = invalid_message(crafted(&bytes, 32, &4u64.to_ne_bytes()));
    assert!(m.contains("payload length"), "{m}");
    let m = invalid_message(crafted(&bytes, 25, &[9]));
    assert!(m.contains("pivot"), "{m}");
    let m = invalid_message(crafted(&bytes, 24, &[2]));
    assert!(m.contains("scalar type code"), "{m}");
    let m = invalid_message(crafted(&bytes, 64, &(info.depth as u64 + 1).to_ne_bytes()));
    assert!(m.contains("depth"), "{m}");

    // A declared size far beyond the input: refused before anything that size is reserved.
    let mut huge = bytes.clone();
    huge[40..48].copy_from_slice(&u64::from(u32::MAX).to_ne_bytes());
    huge[48..56].copy_from_slice(&u64::from(u32::MAX).to_ne_bytes());
    huge[32..40].copy_from_slice(&1000u64.to_ne_bytes());
    reseal(&mut huge);
    assert!(KdTree::<f32>::from_bytes(&huge).is_err());
    assert!(KdTree::<f32>::load(&huge[..]).is_err());

    // The root's right child pointing at itself (a cycle), back to the root, out of range.
    for right in [0u32, 1, 1000] {
        let m = invalid_message(crafted(&bytes, node(0) + 8, &u32s(right)));
        assert!(
            m.contains("node") || m.contains("right child"),
            "{right}: {m}"
        );
    }
    // A split dimension out of range, a NaN split, a split that puts points on the wrong side.
    let m = invalid_message(crafted(&bytes, node(0) + 4, &u32s(3)));
    assert!(m.contains("splits dimension 3"), "{m}");
    let m = invalid_message(crafted(&bytes, node(0), &f32::NAN.to_ne_bytes()));
    assert!(m.contains("splits"), "{m}");
    let m = invalid_message(crafted(&bytes, node(0), &(-1e30f32).to_ne_bytes()));
    assert!(m.contains("left points reach"), "{m}");
    // A duplicated index, an index beyond the source points, a non-finite coordinate.
    let first_id = u32::from_ne_bytes(bytes[ids..ids + 4].try_into().unwrap());
    let m = invalid_message(crafted(&bytes, ids + 4, &u32s(first_id)));
    assert!(m.contains("held twice"), "{m}");
    let m = invalid_message(crafted(&bytes, ids, &u32s(60)));
    assert!(m.contains("not below"), "{m}");
    let m = invalid_message(crafted(&bytes, coords + 4, &f32::INFINITY.to_ne_bytes()));
    assert!(m.contains("non-finite"), "{m}");
    // The bitmap of held indices not matching the indices.
    let bitmap = nodes + 16 * info.nodes;
    let m = invalid_message(crafted(&bytes, bitmap, &[0]));
    assert!(m.contains("bitmap"), "{m}");
}

/// Random changes to the payload and header, resealed: each load is refused or gives a tree
/// that answers exactly what brute force answers over the points it holds.
#[test]
fn resealed_mutations_are_refused_or_answer_exactly() {
    let tree = small_tree();
    let bytes = tree.to_bytes();
    let mut rng = Rng::new(77);
    let (mut loaded, mut refused) = (0, 0);
    for round in 0..3000 {
        let mut b = bytes.clone();
        for _ in 0..1 + rng.below(3) {
            // Mostly the payload; sometimes the header's fields.
            let at = if rng.below(8) == 0 {
                24 + rng.below(96)
            } else {
                HEADER_LEN + rng.below(b.len() - HEADER_LEN)
            };
            match rng.below(3) {
                0 => b[at] ^= 1 << rng.below(8),
                1 => b[at] = rng.below(256) as u8,
                _ => b[at] = b[at].wrapping_add(1),
            }
        }
        reseal(&mut b);
        let Ok(t) = KdTree::<f32>::from_bytes(&b) else {
            refused += 1;
            continue;
        };
        loaded += 1;
        // The points the loaded tree holds, in caller order, as a brute-force reference.
        let n = t.source_len();
        let mut coords = vec![f32::NAN; n * 3];
        for i in 0..n as u32 {
            if let Some(p) = t.point(i) {
                coords[i as usize * 3..i as usize * 3 + 3].copy_from_slice(p);
            }
        }
        let view = PointsView::from_flat(&coords, 3).unwrap();
        let brute = BruteForce::new(&view, NonFinitePolicy::Skip).unwrap();
        let queries = to_f32(&points(Kind::Random, 8, 3, round as u64));
        let (mut a, mut e) = (Vec::new(), Vec::new());
        for nbhd in [
            Neighborhood::Knn { k: 4 },
            Neighborhood::Radius {
                radius: 0.4,
                sorted: true,
            },
        ] {
            for q in queries.chunks_exact(3) {
                t.search(Query::point(q), nbhd, &mut a).unwrap();
                brute.search(Query::point(q), nbhd, &mut e).unwrap();
                assert_eq!(a, e, "round {round}");
            }
            let opts = TableOptions::default();
            assert_eq!(
                t.neighborhoods(nbhd, &opts).unwrap(),
                nbhd::table::neighborhoods_of_all(&brute, nbhd, true).unwrap(),
                "round {round}"
            );
        }
    }
    assert!(refused > 0);
    // Some changes keep a consistent tree (a split moved within its gap, a coordinate moved
    // within its cell): those must be answered exactly, so the check above is not vacuous.
    assert!(loaded > 0, "{refused} refused, none loaded");
}

#[allow(dead_code)]
#[path = "../fuzz/tree_bodies.rs"]
mod tree_bodies;

/// The fuzz seeds of `load_tree` (a mode byte, then a saved tree): the trees below.
/// `NBHD_BLESS_FUZZ_SEEDS=1` writes them.
fn seed_trees() -> Vec<(&'static str, u8, Vec<u8>)> {
    let skip = |pivot, leaf_size| BuildOptions {
        pivot,
        leaf_size,
        non_finite: NonFinitePolicy::Skip,
        ..BuildOptions::default()
    };
    let f32s = |kind, n, d, seed| to_f32(&points(kind, n, d, seed));
    vec![
        ("f32-3d-skipped", 0, small_tree().to_bytes()),
        ("f32-3d-resealed", 1, small_tree().to_bytes()),
        (
            "f64-1d-cyclic-leaf1",
            2,
            build(&cloud(30, 1, 4), 1, skip(PivotPolicy::CyclicMedian, 1)).to_bytes(),
        ),
        (
            "f64-7d-closest",
            3,
            build(&cloud(40, 7, 5), 7, skip(PivotPolicy::ClosestToMiddle, 4)).to_bytes(),
        ),
        (
            "f32-2d-identical",
            1,
            build(
                &f32s(Kind::AllIdentical, 20, 2, 1),
                2,
                skip(PivotPolicy::SpreadMedian, 3),
            )
            .to_bytes(),
        ),
        (
            "f32-3d-one-point",
            0,
            build(&[1.0f32, 2.0, 3.0], 3, BuildOptions::default()).to_bytes(),
        ),
        // Dynamic trees (mode bit 2): batches, removals and a skipped point.
        ("dynamic-f32-3d", 4, small_forest::<f32>(3).to_bytes()),
        (
            "dynamic-f64-2d-resealed",
            7,
            small_forest::<f64>(2).to_bytes(),
        ),
    ]
}

/// A dynamic tree of a few batches with removals and a skipped NaN point.
fn small_forest<T: Scalar>(d: usize) -> nbhd::DynamicKdTree<T> {
    let options = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        leaf_size: 3,
        ..BuildOptions::default()
    };
    let mut f = nbhd::DynamicKdTree::<T>::new(d, &options).unwrap();
    for (batch, n) in [20usize, 9, 5, 12].into_iter().enumerate() {
        let mut c = cloud(n, d, 40 + batch as u64);
        c[0] = f64::NAN;
        let c: Vec<T> = c.into_iter().map(T::from_f64).collect();
        let first = f.insert_flat(&c).unwrap();
        f.remove(&[first + 1, first + 3]).unwrap();
    }
    f
}

fn data_dir(sub: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(sub)
        .join("load_tree")
}

fn files_in(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn fuzz_seeds_and_regressions_through_the_loader() {
    let seeds = data_dir("fuzz-seeds");
    if std::env::var_os("NBHD_BLESS_FUZZ_SEEDS").is_some() {
        std::fs::create_dir_all(&seeds).unwrap();
        for (name, mode, bytes) in seed_trees() {
            let mut b = vec![mode];
            b.extend_from_slice(&bytes);
            std::fs::write(seeds.join(name), b).unwrap();
        }
    }
    let files = files_in(&seeds);
    assert_eq!(
        files.len(),
        seed_trees().len(),
        "seeds in {}",
        seeds.display()
    );
    for path in &files {
        let bytes = std::fs::read(path).unwrap();
        // Each seed is a valid tree of the type its mode byte names.
        let tree = &bytes[1..];
        let ok = match bytes[0] & 6 {
            0 => KdTree::<f32>::from_bytes(tree).is_ok(),
            2 => KdTree::<f64>::from_bytes(tree).is_ok(),
            4 => nbhd::DynamicKdTree::<f32>::from_bytes(tree).is_ok(),
            _ => nbhd::DynamicKdTree::<f64>::from_bytes(tree).is_ok(),
        };
        assert!(ok, "{}", path.display());
        tree_bodies::load_tree(&bytes);
    }
    for path in files_in(&data_dir("fuzz-regressions")) {
        tree_bodies::load_tree(&std::fs::read(&path).unwrap());
    }
    // Seeded mutations of the seeds, resealed or not, f32 or f64.
    let mut rng = Rng::new(5);
    for round in 0..4000 {
        let mut b = std::fs::read(&files[round % files.len()]).unwrap();
        // The seed's kind (static or dynamic) kept, the scalar type and resealing drawn.
        b[0] = (b[0] & 4) | rng.below(4) as u8;
        for _ in 0..1 + rng.below(4) {
            let at = 1 + rng.below(b.len() - 1);
            b[at] = match rng.below(3) {
                0 => b[at] ^ (1 << rng.below(8)),
                1 => rng.below(256) as u8,
                _ => b[at].wrapping_sub(1),
            };
        }
        if rng.below(10) == 0 {
            b.truncate(1 + rng.below(b.len() - 1));
        }
        tree_bodies::load_tree(&b);
    }
}
