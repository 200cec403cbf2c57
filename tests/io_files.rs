//! nbhd::io: round trips through every writable format, the real files of tests/data, and
//! malformed input whose errors must name the place.
#![cfg(feature = "io")]

use nbhd::io::{
    self, Encoding, Format, Grid, IoErrorKind, Location, PointCloud, Precision, ReadOptions,
    Viewpoint, WriteOptions,
};
use std::path::PathBuf;

/// The real scans of `tests/data` (see its README). They are part of the repository, so a
/// missing folder is a broken checkout and fails the test rather than skipping it. (The
/// `Option` stays so that tests written against the old optional data keep compiling.)
fn data_dir() -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    assert!(
        d.join("pcl").is_dir(),
        "{} is missing: the test data belongs to the repository",
        d.display()
    );
    Some(d)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("nbhd-io-test-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// 4 x 3 organized cloud with a NaN hole, normals, and two scalar fields.
fn sample() -> PointCloud {
    let mut c = PointCloud::default();
    for i in 0..12 {
        let f = i as f64;
        c.positions
            .push([f * 0.1 + 1.0 / 3.0, -f * 1e-7, f.sin() * 1e5]);
    }
    c.positions[5] = [f64::NAN; 3];
    c.set_normals(
        (0..12)
            .map(|i| [0.0, (i as f64).cos(), (i as f64).sin()])
            .collect(),
    )
    .unwrap();
    c.set_scalar("curvature", (0..12).map(|i| i as f64 / 7.0).collect())
        .unwrap();
    c.set_scalar("intensity", (0..12).map(|i| (i * 100) as f64).collect())
        .unwrap();
    c.grid = Some(Grid {
        width: 4,
        height: 3,
    });
    c
}

fn same(a: f64, b: f64) -> bool {
    a == b || (a.is_nan() && b.is_nan())
}

fn assert_close(a: &PointCloud, b: &PointCloud, single: bool, what: &str) {
    let r = |v: f64| if single { v as f32 as f64 } else { v };
    assert_eq!(a.len(), b.len(), "{what}: count");
    for (i, (p, q)) in a.positions.iter().zip(&b.positions).enumerate() {
        for j in 0..3 {
            assert!(
                same(r(p[j]), r(q[j])),
                "{what}: point {i} coord {j}: {} vs {}",
                p[j],
                q[j]
            );
        }
    }
    let (na, nb) = (
        a.normals.as_ref().unwrap(),
        b.normals.as_ref().expect("normals lost"),
    );
    for (p, q) in na.iter().zip(nb) {
        for j in 0..3 {
            assert!(same(r(p[j]), r(q[j])), "{what}: normal");
        }
    }
    assert_eq!(a.scalars.len(), b.scalars.len(), "{what}: scalar fields");
    for (s, t) in a.scalars.iter().zip(&b.scalars) {
        assert_eq!(s.name, t.name, "{what}");
        for (x, y) in s.values.iter().zip(&t.values) {
            assert!(same(r(*x), r(*y)), "{what}: scalar {}", s.name);
        }
    }
}

#[test]
fn round_trips_every_writable_format() {
    let c = sample();
    let cases = [
        ("ply", Some(Encoding::Ascii)),
        ("ply", Some(Encoding::Binary)),
        ("ply", Some(Encoding::BinaryBigEndian)),
        ("pcd", Some(Encoding::Ascii)),
        ("pcd", Some(Encoding::Binary)),
        ("pcd", Some(Encoding::BinaryCompressed)),
        ("xyz", None),
    ];
    let mut n = 0;
    for (ext, encoding) in cases {
        for precision in [Precision::Double, Precision::Single] {
            let what = format!("{ext} {encoding:?} {precision:?}");
            let path = tmp(&format!("rt-{n}.{ext}"));
            n += 1;
            let opts = WriteOptions {
                format: None,
                encoding,
                precision,
            };
            io::write(&path, &c, &opts).unwrap_or_else(|e| panic!("{what}: {e}"));
            let back = io::read(&path).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_close(&c, &back, precision == Precision::Single, &what);
            assert_eq!(back.non_finite_count(), 1, "{what}");
            if ext == "pcd" {
                assert_eq!(back.grid, c.grid, "{what}: grid");
            }
            // The in-memory path gives the same bytes and the same cloud.
            let fmt = Format::from_path(&path).unwrap();
            let bytes = io::write_bytes(&c, fmt, &opts).unwrap();
            assert_eq!(bytes, std::fs::read(&path).unwrap(), "{what}");
            assert_eq!(io::read_bytes(&bytes, fmt).unwrap().len(), c.len());
            std::fs::remove_file(&path).unwrap();
        }
    }
}

#[test]
fn positions_only_round_trip_has_no_normals() {
    let c = PointCloud::from_positions(vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.5]]);
    for ext in ["ply", "pcd", "xyz"] {
        let path = tmp(&format!("plain.{ext}"));
        io::write(&path, &c, &WriteOptions::default()).unwrap();
        let back = io::read(&path).unwrap();
        assert_eq!(back.positions, c.positions, "{ext}");
        assert_eq!(back.field_names(), ["x", "y", "z"]);
        // Written as float by default, and read as such.
        assert_eq!(back.source_precision, Some(Precision::Single), "{ext}");
    }
}

#[test]
fn ply_header_names_normals_and_scalars_as_viewers_expect() {
    // Float by default: what PCL's loaders match.
    let bytes = io::write_bytes(&sample(), Format::Ply, &WriteOptions::ascii()).unwrap();
    let text = String::from_utf8(bytes).unwrap();
    for line in [
        "format ascii 1.0",
        "element vertex 12",
        "property float x",
        "property float nx",
        "property float nz",
        "property float curvature",
        "end_header",
    ] {
        assert!(text.contains(line), "missing '{line}' in\n{text}");
    }
    let double = WriteOptions {
        precision: Precision::Double,
        ..WriteOptions::ascii()
    };
    let text =
        String::from_utf8(io::write_bytes(&sample(), Format::Ply, &double).unwrap()).unwrap();
    assert!(text.contains("property double x\n"));
    assert!(text.contains("property double curvature"));
    let single = WriteOptions::ascii();
    let text =
        String::from_utf8(io::write_bytes(&sample(), Format::Ply, &single).unwrap()).unwrap();
    assert!(
        text.contains("nan nan nan"),
        "NaN written as C and PCL write it"
    );
}

#[test]
fn reads_ply_with_faces_lists_and_other_elements() {
    let ascii = b"ply\nformat ascii 1.0\ncomment x\nelement camera 1\nproperty float a\n\
element vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n\
property list uchar int extra\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
7\n0 0 0 255 2 1 1\n1 0 0 0 0\n0 1 0 10 1 5\n3 0 1 2\n";
    let c = io::read_bytes(ascii, Format::Ply).unwrap();
    assert_eq!(c.len(), 3);
    assert_eq!(c.positions[2], [0.0, 1.0, 0.0]);
    assert_eq!(c.scalar("red").unwrap(), [255.0, 0.0, 10.0]);

    // The same in binary big endian, with a camera element and a list before the data.
    let mut b =
        b"ply\nformat binary_big_endian 1.0\nelement camera 1\nproperty list uchar short a\n\
element vertex 2\nproperty short x\nproperty int y\nproperty double z\nproperty float normal_x\n\
property float normal_y\nproperty float normal_z\nend_header\n"
            .to_vec();
    b.extend([2, 0, 1, 0, 2]);
    for (x, y, z) in [(-3i16, 7i32, 0.5f64), (4, -8, 1e10)] {
        b.extend(x.to_be_bytes());
        b.extend(y.to_be_bytes());
        b.extend(z.to_be_bytes());
        b.extend(0f32.to_be_bytes());
        b.extend(0f32.to_be_bytes());
        b.extend(1f32.to_be_bytes());
    }
    let c = io::read_bytes(&b, Format::Ply).unwrap();
    assert_eq!(c.positions, vec![[-3.0, 7.0, 0.5], [4.0, -8.0, 1e10]]);
    assert_eq!(c.normals.unwrap()[1], [0.0, 0.0, 1.0]);
}

#[test]
fn reads_xyz_variants() {
    let c = io::read_bytes(b"1 2 3\n4,5,6\n\n7;8;9\n", Format::Xyz).unwrap();
    assert_eq!(c.len(), 3);
    assert!(c.normals.is_none());
    let c = io::read_bytes(b"//X Y Z Nx Ny Nz\n1 2 3 0 0 1\n", Format::Xyz).unwrap();
    assert_eq!(c.normals.unwrap(), vec![[0.0, 0.0, 1.0]]);
    let c = io::read_bytes(b"1 2 3 0 0 1\nnan nan nan 0 1 0\n", Format::Xyz).unwrap();
    assert_eq!(c.non_finite_count(), 1);
    assert!(c.normals.is_some());
    let c = io::read_bytes(b"1 2 3 0.5\n", Format::Xyz).unwrap();
    assert_eq!(c.scalar("field3").unwrap(), [0.5]);
}

#[test]
fn pcd_with_counts_padding_and_integer_types() {
    let text = b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z _ label hist\nSIZE 4 4 8 1 2 4\n\
TYPE F F F U U F\nCOUNT 1 1 1 1 1 2\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n\
1 2 3 0 7 0.5 0.25\nnan nan nan 0 8 1 2\n";
    let c = io::read_bytes(text, Format::Pcd).unwrap();
    assert_eq!(c.len(), 2);
    assert_eq!(c.non_finite_count(), 1);
    assert_eq!(c.scalar("label").unwrap(), [7.0, 8.0]);
    assert_eq!(c.scalar("hist_1").unwrap(), [0.25, 2.0]);
    assert_eq!(c.grid, None);
}

fn check_real(rel: &str, points: usize, nan: Option<usize>, grid: Option<(usize, usize)>) {
    let Some(dir) = data_dir() else { return };
    let c = io::read(dir.join(rel)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(c.len(), points, "{rel}");
    c.validate().unwrap();
    if let Some(k) = nan {
        assert_eq!(c.non_finite_count(), k, "{rel}: NaN points");
    }
    assert_eq!(
        c.grid.map(|g| (g.width, g.height)),
        grid,
        "{rel}: organized"
    );
    let b = c.bounding_box().expect("finite points");
    assert!(b.diagonal() > 0.0 && b.diagonal().is_finite(), "{rel}");
}

#[test]
fn real_pcd_ascii_bunny() {
    check_real("pcl/bunny.pcd", 397, Some(0), None);
}

#[test]
fn real_pcd_compressed_milk() {
    check_real("pcl/milk.pcd", 13_704, Some(0), None);
}

#[test]
fn real_pcd_compressed_cturtle_with_intensity() {
    check_real("pcl/cturtle.pcd", 167_198, None, None);
    if let Some(dir) = data_dir() {
        let c = io::read(dir.join("pcl/cturtle.pcd")).unwrap();
        assert_eq!(c.field_names(), ["x", "y", "z", "intensity"]);
    }
}

#[test]
fn real_pcd_compressed_mug_with_nan_holes() {
    check_real(
        "pcl/table_scene_mug_stereo_textured.pcd",
        307_200,
        Some(97_920),
        Some((640, 480)),
    );
}

#[test]
fn real_pcd_compressed_office_organized() {
    check_real("pcl/office1.pcd", 307_200, None, Some((640, 480)));
}

#[test]
fn real_obj_vertices() {
    check_real("meshes/stanford-bunny.obj", 35_947, Some(0), None);
    check_real("meshes/fandisk.obj", 6_475, Some(0), None);
}

#[test]
fn real_compressed_cloud_survives_conversion() {
    let Some(dir) = data_dir() else { return };
    let c = io::read(dir.join("pcl/milk.pcd")).unwrap();
    let bytes = io::write_bytes(&c, Format::Ply, &WriteOptions::default()).unwrap();
    assert_eq!(io::read_bytes(&bytes, Format::Ply).unwrap(), c);
}

fn err_of(data: &[u8], format: Format) -> io::IoError {
    match io::read_bytes(data, format) {
        Ok(c) => panic!("expected an error, read {} points", c.len()),
        Err(e) => e,
    }
}

#[test]
fn malformed_files_name_the_place() {
    // A bad number in ascii PLY: its line.
    let e = err_of(
        b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
property float z\nend_header\n0 0 0\n1 zero 0\n",
        Format::Ply,
    );
    assert_eq!(e.location, Some(Location::Line(9)), "{e}");
    assert!(
        e.to_string().contains("<memory>: line 9: vertex 1: 'zero'"),
        "{e}"
    );

    // Truncated binary PLY: the element line whose count the data cannot hold.
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
property float y\nproperty float z\nend_header\n"
        .to_vec();
    b.extend([0u8; 12 + 5]);
    let e = err_of(&b, Format::Ply);
    assert_eq!(e.location, Some(Location::Line(3)), "{e}");
    assert!(
        e.to_string()
            .contains("3 records of at least 12 bytes, but only 17 bytes"),
        "{e}"
    );

    // Truncated binary PLY with a list: the byte where the cut record starts.
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n\
property float y\nproperty float z\nproperty list uchar int l\nend_header\n"
        .to_vec();
    let header = b.len();
    b.extend([0u8; 13]); // vertex 0, empty list
    b.extend([0u8; 12]);
    b.push(3); // vertex 1: a list of 3 ints that is not there
    let e = err_of(&b, Format::Ply);
    assert_eq!(
        e.location,
        Some(Location::Byte((header + 13) as u64)),
        "{e}"
    );

    // An unknown PLY header keyword.
    let e = err_of(
        b"ply\nformat ascii 1.0\nelemnt vertex 1\nend_header\n",
        Format::Ply,
    );
    assert_eq!(e.location, Some(Location::Line(3)), "{e}");

    // PCD: SIZE and FIELDS disagree.
    let e = err_of(
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n0 0 0\n",
        Format::Pcd,
    );
    assert_eq!(e.location, Some(Location::Line(3)), "{e}");

    // PCD ascii with too few points: the last line.
    let e = err_of(
        b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n0 0 0\n1 1 1\n",
        Format::Pcd,
    );
    assert_eq!(e.location, Some(Location::Line(9)), "{e}");

    // PCD binary_compressed with a corrupt LZF stream: a byte offset inside the data.
    let head = b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_compressed\n";
    let mut b = head.to_vec();
    b.extend(4u32.to_le_bytes());
    b.extend(12u32.to_le_bytes());
    b.extend([0x20, 0x05, 0, 0]); // a back reference before any output
    let e = err_of(&b, Format::Pcd);
    assert_eq!(
        e.location,
        Some(Location::Byte((head.len() + 8) as u64)),
        "{e}"
    );
    assert!(e.to_string().contains("corrupt LZF"), "{e}");

    // PCD without x.
    let e = err_of(
        b"FIELDS a y z\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
        Format::Pcd,
    );
    assert!(e.to_string().contains("no 'x' field"), "{e}");

    // XYZ with a changing column count.
    let e = err_of(b"1 2 3\n4 5 6\n7 8\n", Format::Xyz);
    assert_eq!(e.location, Some(Location::Line(3)), "{e}");

    // OBJ with a short vertex.
    let e = err_of(b"# c\nv 1 2 3\nv 1 2\nf 1 2 3\n", Format::Obj);
    assert_eq!(e.location, Some(Location::Line(3)), "{e}");
}

#[test]
fn unsupported_and_missing_files_say_so() {
    let p = tmp("scan.e57");
    std::fs::write(&p, b"ASTM-E57....").unwrap();
    let e = io::read(&p).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::Unsupported(_)));
    assert!(
        e.to_string().contains("scan.e57") && e.to_string().contains("E57"),
        "{e}"
    );
    // A LAS file cut after its signature is malformed, not unsupported.
    let p = tmp("scan.las");
    std::fs::write(&p, b"LASF....").unwrap();
    let e = io::read(&p).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::Malformed(_)), "{e}");
    assert!(e.to_string().contains("scan.las"), "{e}");

    let p = tmp("does-not-exist.ply");
    let e = io::read(&p).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::Io(_)));
    assert!(e.to_string().contains("does-not-exist.ply"), "{e}");

    let c = PointCloud::from_positions(vec![[0.0; 3]]);
    for (name, enc) in [
        ("a.obj", None),
        ("a.xyz", Some(Encoding::Binary)),
        ("a.pcd", Some(Encoding::BinaryBigEndian)),
    ] {
        let opts = WriteOptions {
            encoding: enc,
            ..WriteOptions::default()
        };
        let e = io::write(tmp(name), &c, &opts).unwrap_err();
        assert!(matches!(e.kind, IoErrorKind::Unsupported(_)), "{name}: {e}");
        assert!(!tmp(name).exists(), "a refused write leaves no file");
    }

    let mut bad = c.clone();
    bad.normals = Some(vec![]);
    let e = io::write(tmp("bad.ply"), &bad, &WriteOptions::default()).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::InvalidCloud(_)), "{e}");
}

mod prop {
    use super::*;
    use proptest::prelude::*;

    fn coord() -> impl Strategy<Value = f64> {
        prop_oneof![
            8 => any::<f64>().prop_filter("finite", |v| v.is_finite()),
            1 => Just(f64::NAN),
            1 => Just(f64::INFINITY),
            1 => Just(-0.0),
        ]
    }

    fn cloud() -> impl Strategy<Value = PointCloud> {
        (1usize..40, any::<bool>(), 0usize..3).prop_flat_map(|(n, normals, ns)| {
            (
                proptest::collection::vec([coord(), coord(), coord()], n),
                proptest::collection::vec([coord(), coord(), coord()], if normals { n } else { 0 }),
                proptest::collection::vec(proptest::collection::vec(coord(), n), ns),
            )
                .prop_map(move |(p, nr, sc)| {
                    let mut c = PointCloud::from_positions(p);
                    if normals {
                        c.set_normals(nr).unwrap();
                    }
                    for (k, v) in sc.into_iter().enumerate() {
                        c.set_scalar(&format!("s{k}"), v).unwrap();
                    }
                    c
                })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Double precision is exact in every writable format and encoding, NaN and
        /// infinities included.
        #[test]
        fn double_precision_round_trips_exactly(c in cloud()) {
            for (format, enc) in [
                (Format::Ply, Encoding::Ascii),
                (Format::Ply, Encoding::Binary),
                (Format::Ply, Encoding::BinaryBigEndian),
                (Format::Pcd, Encoding::Ascii),
                (Format::Pcd, Encoding::Binary),
                (Format::Pcd, Encoding::BinaryCompressed),
                (Format::Xyz, Encoding::Ascii),
            ] {
                let opts = WriteOptions { format: None, encoding: Some(enc), precision: Precision::Double };
                let bytes = io::write_bytes(&c, format, &opts).unwrap();
                let back = io::read_bytes(&bytes, format).unwrap();
                let what = format!("{format:?} {enc:?}");
                prop_assert_eq!(back.len(), c.len());
                let bits = |v: &[[f64; 3]]| v.iter().flatten().map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() }).collect::<Vec<_>>();
                prop_assert_eq!(bits(&back.positions), bits(&c.positions), "{}", what);
                prop_assert_eq!(back.normals.as_deref().map(bits), c.normals.as_deref().map(bits), "{}", what);
                prop_assert_eq!(back.scalars.len(), c.scalars.len());
                for (s, t) in back.scalars.iter().zip(&c.scalars) {
                    prop_assert_eq!(&s.name, &t.name);
                    let b: Vec<u64> = s.values.iter().map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() }).collect();
                    let a: Vec<u64> = t.values.iter().map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() }).collect();
                    prop_assert_eq!(a, b, "{}", what);
                }
            }
        }
    }
}

#[test]
fn packed_colours_keep_their_bits() {
    // rgb stored as the bits of a float; 0xFFAABBCC is a signalling-NaN pattern that a
    // float conversion would alter.
    let mut b = b"VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n\
WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n"
        .to_vec();
    for c in [0xFFAABBCCu32, 0x00102030] {
        b.extend(1f32.to_le_bytes());
        b.extend(2f32.to_le_bytes());
        b.extend(3f32.to_le_bytes());
        b.extend(c.to_le_bytes());
    }
    let c = io::read_bytes(&b, Format::Pcd).unwrap();
    assert_eq!(
        c.scalar("rgb").unwrap(),
        [0xFFAABBCCu32 as f64, 0x00102030 as f64]
    );
    assert_eq!(
        c.colors().unwrap(),
        vec![[0xAA, 0xBB, 0xCC], [0x10, 0x20, 0x30]]
    );
    let single = WriteOptions {
        precision: Precision::Single,
        encoding: Some(Encoding::Binary),
        ..WriteOptions::default()
    };
    let out = io::write_bytes(&c, Format::Pcd, &single).unwrap();
    let text = String::from_utf8_lossy(&out);
    // PCL's PointXYZRGB: rgb is a 4-byte float holding the packed bits.
    assert!(
        text.contains("FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\n"),
        "{text}"
    );
    assert_eq!(&out[out.len() - 16 + 12..], &0x00102030u32.to_le_bytes());
    assert_eq!(
        &out[out.len() - 32 + 12..out.len() - 16],
        &0xFFAABBCCu32.to_le_bytes()
    );
    for (format, opts) in [
        (Format::Ply, WriteOptions::ascii()),
        (Format::Ply, single),
        (Format::Pcd, WriteOptions::ascii()),
        (
            Format::Xyz,
            WriteOptions {
                precision: Precision::Single,
                ..WriteOptions::default()
            },
        ),
    ] {
        let bytes = io::write_bytes(&c, format, &opts).unwrap();
        let back = io::read_bytes(&bytes, format).unwrap();
        assert_eq!(back.colors(), c.colors(), "{format:?}");
        if format == Format::Pcd {
            // PCD keeps the packed bits, alpha included.
            assert_eq!(back.scalar("rgb"), c.scalar("rgb"), "{format:?}");
        } else {
            // PLY and XYZ: 8-bit red green blue, as MeshLab and CloudCompare read them.
            assert_eq!(back.field_names(), ["x", "y", "z", "red", "green", "blue"]);
            let text = String::from_utf8_lossy(&bytes);
            if format == Format::Ply {
                assert!(
                    text.contains(
                        "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                    ),
                    "{text}"
                );
            }
        }
    }
    // Colours given as channels go to PCD as 0x00RRGGBB.
    let mut ch = PointCloud::from_positions(vec![[0.0; 3]]);
    ch.set_scalar("red", vec![1.0]).unwrap();
    ch.set_scalar("green", vec![2.0]).unwrap();
    ch.set_scalar("blue", vec![255.0]).unwrap();
    let out = io::write_bytes(&ch, Format::Pcd, &WriteOptions::ascii()).unwrap();
    assert!(String::from_utf8_lossy(&out).ends_with("\n0 0 0 66303\n"));
    // PCL's ascii form: the float printed as a number.
    let f = f32::from_bits(0x00102030);
    let t = format!("FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0 0 {f:e}\n");
    let c = io::read_bytes(t.as_bytes(), Format::Pcd).unwrap();
    assert_eq!(c.colors().unwrap(), vec![[0x10, 0x20, 0x30]]);
}

#[test]
fn real_office_scan_has_colours() {
    let Some(dir) = data_dir() else { return };
    let c = io::read(dir.join("pcl/office1.pcd")).unwrap();
    let colors = c.colors().expect("rgb field");
    let distinct: std::collections::HashSet<_> = colors.iter().collect();
    assert!(distinct.len() > 1000, "{} colours", distinct.len());
    // Through binary PCD and back: the same packed values.
    let bytes = io::write_bytes(&c, Format::Pcd, &WriteOptions::default()).unwrap();
    let back = io::read_bytes(&bytes, Format::Pcd).unwrap();
    assert_eq!(back.scalar("rgb"), c.scalar("rgb"));
}

/// Issue 16, item 2: header counts are never trusted. Each of these files once aborted
/// (allocation failure, capacity overflow), hung or read as empty with success; each must be an
/// error naming the header line, quickly.
#[test]
fn hostile_header_counts_are_errors_naming_the_line() {
    let ply_xyz = |fmt: &str, count: &str| {
        format!(
            "ply\nformat {fmt} 1.0\nelement vertex {count}\nproperty float x\nproperty float y\n\
             property float z\nend_header\n"
        )
        .into_bytes()
    };
    let pcd = |fields: &str, count: &str, points: &str, data: &str| {
        format!(
            "VERSION 0.7\nFIELDS {fields}\nSIZE 4 4 4\nTYPE F F F\nCOUNT {count}\nWIDTH {points}\n\
             HEIGHT 1\nPOINTS {points}\nDATA {data}\n"
        )
        .into_bytes()
    };
    let start = std::time::Instant::now();
    let mut cases: Vec<(&str, Vec<u8>, Format, usize)> = Vec::new();

    // A 148-byte binary PLY declaring 4e9 vertices, and 2^64 - 1 vertices.
    let mut b = ply_xyz("binary_little_endian", "4000000000");
    b.resize(148, 0);
    cases.push(("PLY 4e9 vertices", b, Format::Ply, 3));
    let mut b = ply_xyz("binary_little_endian", &u64::MAX.to_string());
    b.extend([0u8; 24]);
    cases.push(("PLY 2^64-1 vertices", b, Format::Ply, 3));
    let mut b = ply_xyz("ascii", &u64::MAX.to_string());
    b.extend(b"0 0 0\n1 1 1\n");
    cases.push(("ascii PLY 2^64-1 vertices", b, Format::Ply, 0));
    // An element without properties and 2^64 - 1 records before the vertices (once a hang).
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement nothing {}\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nend_header\n",
        u64::MAX,
        u64::MAX
    )
    .into_bytes();
    b.extend([0u8; 12]);
    cases.push(("PLY empty element 2^64-1 then vertices", b, Format::Ply, 4));
    // An element with properties and a huge count before the vertices.
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement face {}\nproperty list uchar int v\n\
         element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
        u64::MAX / 2
    )
    .into_bytes();
    b.extend([0u8; 12]);
    cases.push(("PLY huge face element", b, Format::Ply, 3));

    // PCD: POINTS 10^12 in binary, ascii and binary_compressed.
    let tera = "1000000000000";
    let mut b = pcd("x y z", "1 1 1", tera, "binary");
    b.extend([0u8; 24]);
    cases.push(("PCD binary POINTS 1e12", b, Format::Pcd, 8));
    let mut b = pcd("x y z", "1 1 1", tera, "ascii");
    b.extend(b"0 0 0\n");
    cases.push(("PCD ascii POINTS 1e12", b, Format::Pcd, 8));
    let mut b = pcd("x y z", "1 1 1", tera, "binary_compressed");
    b.extend([0u8; 16]);
    cases.push(("PCD compressed POINTS 1e12", b, Format::Pcd, 8));
    // COUNT 1 1 10^12.
    let mut b = pcd("x y z", &format!("1 1 {tera}"), "1", "binary");
    b.extend([0u8; 24]);
    cases.push(("PCD COUNT 1 1 1e12", b, Format::Pcd, 5));
    // COUNT that overflows the sum.
    let mut b = pcd(
        "x y z",
        &format!("1 {} {}", usize::MAX, usize::MAX),
        "1",
        "ascii",
    );
    b.extend(b"0 0 0\n");
    cases.push(("PCD COUNT overflow", b, Format::Pcd, 5));
    // WIDTH x HEIGHT overflows (once 0 points with success).
    let b = b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n\
WIDTH 4294967296\nHEIGHT 4294967296\nDATA binary\n"
        .to_vec();
    cases.push(("PCD WIDTH x HEIGHT overflow", b, Format::Pcd, 7));

    for (what, data, format, line) in &cases {
        let e = err_of(data, *format);
        assert!(matches!(e.kind, IoErrorKind::Malformed(_)), "{what}: {e:?}");
        if *line > 0 {
            assert_eq!(e.location, Some(Location::Line(*line)), "{what}: {e}");
        }
        println!("{what}: {e}");
    }

    // binary_compressed declaring 357,913,941 points (about 4 GiB) in a few bytes of LZF.
    let mut b = pcd("x y z", "1 1 1", "357913941", "binary_compressed");
    let at = b.len();
    b.extend(16u32.to_le_bytes());
    b.extend((357_913_941u32 * 12).to_le_bytes());
    b.extend([0u8; 16]);
    let e = err_of(&b, Format::Pcd);
    assert_eq!(e.location, Some(Location::Byte((at + 4) as u64)), "{e}");
    assert!(e.to_string().contains("cannot come from 16 bytes"), "{e}");

    assert!(
        start.elapsed().as_secs_f64() < 5.0,
        "hostile headers took {:?}",
        start.elapsed()
    );
}

/// Issue 13, item 5: text headers are recognised, colours are not taken for normals, and the
/// reader says what it read.
#[test]
fn text_columns_by_header_option_or_values_and_said() {
    let read = |data: &[u8], cols: Option<&[&str]>| {
        let opts = io::ReadOptions {
            columns: cols.map(|c| c.iter().map(|s| s.to_string()).collect()),
            ..Default::default()
        };
        io::read_bytes_with(data, Format::Xyz, &opts).unwrap()
    };
    // Header lines without a comment marker, with commas, and CloudCompare's.
    for (data, names) in [
        (&b"x y z\n1 2 3\n"[..], vec!["x", "y", "z"]),
        (
            b"x,y,z,intensity\n1,2,3,7\n",
            vec!["x", "y", "z", "intensity"],
        ),
        (
            b"//X,Y,Z,R,G,B\n1,2,3,255,0,10\n",
            vec!["x", "y", "z", "red", "green", "blue"],
        ),
        (
            b"# x y z nx ny nz\n1 2 3 0 0.6 0.8\n",
            vec!["x", "y", "z", "nx", "ny", "nz"],
        ),
    ] {
        let (c, info) = read(data, None);
        let t = info.text_columns.unwrap();
        assert_eq!(t.names, names);
        assert_eq!(t.from, "the header on line 1");
        assert_eq!(c.positions, vec![[1.0, 2.0, 3.0]]);
    }
    let (c, _) = read(b"//X,Y,Z,R,G,B\n1,2,3,255,0,10\n", None);
    assert_eq!(c.colors().unwrap(), vec![[255, 0, 10]]);
    assert!(c.normals.is_none());

    // No header, 6 columns of 0..255 integers: a colour, not normals, and said so.
    let (c, info) = read(b"1 2 3 255 128 0\n4 5 6 0 0 1\n", None);
    assert!(c.normals.is_none());
    assert_eq!(c.colors().unwrap(), vec![[255, 128, 0], [0, 0, 1]]);
    let t = info.text_columns.unwrap();
    assert_eq!(t.names, ["x", "y", "z", "red", "green", "blue"]);
    assert!(t.from.contains("0..255"), "{}", t.from);
    // Unit vectors: normals.
    let (c, info) = read(b"1 2 3 0 0 1\n4 5 6 0.6 0.8 0\n", None);
    assert_eq!(c.normals.unwrap()[1], [0.6, 0.8, 0.0]);
    assert!(info.text_columns.unwrap().from.contains("unit vectors"));
    // Neither: scalars.
    let (c, _) = read(b"1 2 3 0.5 7 1000\n", None);
    assert!(c.normals.is_none() && c.colors().is_none());
    assert_eq!(c.scalar("field5").unwrap(), [1000.0]);
    // The caller's names win over the header and the values.
    let (c, info) = read(
        b"x y z a b c\n1 2 3 0 0 1\n",
        Some(&["x", "y", "z", "r", "g", "b"]),
    );
    assert_eq!(c.colors().unwrap(), vec![[0, 0, 1]]);
    assert_eq!(info.text_columns.unwrap().from, "the column names given");
    // Counts that disagree are errors naming the line.
    let e = io::read_bytes_with(b"x y z nx ny nz\n1 2 3\n", Format::Xyz, &Default::default())
        .unwrap_err();
    assert_eq!(e.location, Some(Location::Line(1)), "{e}");
    let opts = io::ReadOptions {
        columns: Some(vec!["x".into(), "y".into()]),
        ..Default::default()
    };
    let e = io::read_bytes_with(b"\n1 2 3\n", Format::Xyz, &opts).unwrap_err();
    assert_eq!(e.location, Some(Location::Line(2)), "{e}");
}

/// `c` written as PCD in each encoding.
fn pcd_encodings(c: &PointCloud) -> Vec<(Encoding, Vec<u8>)> {
    [
        Encoding::Ascii,
        Encoding::Binary,
        Encoding::BinaryCompressed,
    ]
    .into_iter()
    .map(|enc| {
        let opts = WriteOptions {
            encoding: Some(enc),
            ..WriteOptions::default()
        };
        (enc, io::write_bytes(c, Format::Pcd, &opts).unwrap())
    })
    .collect()
}

/// Issue 41 item 5: a PCD's `VIEWPOINT` (office1.pcd: `0 0 0 0 1 0 0`, a half turn about x)
/// and header comments come back in every PCD encoding; PLY, which has no place for the
/// viewpoint, names it in `not_written`.
#[test]
fn pcd_viewpoint_and_comments_come_back() {
    let Some(dir) = data_dir() else { return };
    let mut c = io::read(dir.join("pcl/office1.pcd")).unwrap();
    let turned = Viewpoint {
        origin: [0.0; 3],
        orientation: [0.0, 1.0, 0.0, 0.0],
    };
    assert_eq!(c.metadata.viewpoint, Some(turned));
    c.metadata.comments = vec!["scanned by a Kinect".into()];
    for (enc, bytes) in pcd_encodings(&c) {
        let head = String::from_utf8_lossy(&bytes[..300]).to_string();
        assert!(
            head.contains("\nVIEWPOINT 0 0 0 0 1 0 0\n"),
            "{enc:?}: {head}"
        );
        assert!(
            head.contains("\n# scanned by a Kinect\n"),
            "{enc:?}: {head}"
        );
        let back = io::read_bytes(&bytes, Format::Pcd).unwrap();
        assert_eq!(back.metadata, c.metadata, "{enc:?}");
    }
    assert_eq!(
        io::not_written(&c, Format::Ply),
        ["the PCD viewpoint 0 0 0 0 1 0 0"]
    );
    assert!(io::not_written(&c, Format::Pcd).is_empty());
    // The identity is PCL's default, as good as no viewpoint.
    let milk = io::read(dir.join("pcl/milk.pcd")).unwrap();
    assert_eq!(milk.metadata.viewpoint, None);
}

/// PLY comments (and `obj_info`) come back; what the cloud does not carry, a PLY's faces and
/// list properties or an OBJ's faces, is said by the reader.
#[test]
fn ply_comments_come_back_and_what_is_not_carried_is_said() {
    let ascii = b"ply\nformat ascii 1.0\ncomment made by a scanner\nobj_info 2 cameras\n\
element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
property list uchar int extra\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 1 1\n1 0 0 0\n0 1 0 1 5\n3 0 1 2\n";
    let (c, info) = io::read_bytes_with(ascii, Format::Ply, &ReadOptions::default()).unwrap();
    assert_eq!(
        c.metadata.comments,
        ["made by a scanner", "obj_info 2 cameras"]
    );
    assert_eq!(
        info.not_carried,
        ["1 face element(s)", "the vertices' list property 'extra'"]
    );
    let bytes = io::write_bytes(&c, Format::Ply, &WriteOptions::ascii()).unwrap();
    let text = String::from_utf8_lossy(&bytes).to_string();
    assert!(
        text.contains("comment made by a scanner\nobj_info 2 cameras\n"),
        "{text}"
    );
    // nbhd's own comment is not carried twice.
    let back = io::read_bytes(&bytes, Format::Ply).unwrap();
    assert_eq!(back.metadata.comments, c.metadata.comments);
    assert_eq!(text.matches("written by nbhd").count(), 1);
    assert_eq!(
        io::not_written(&back, Format::Xyz),
        ["2 header comment line(s)"]
    );

    let Some(dir) = data_dir() else { return };
    let opts = ReadOptions::default();
    let (_, info) = io::read_with(dir.join("meshes/fandisk.obj"), &opts).unwrap();
    assert!(
        info.not_carried.iter().any(|n| n == "12946 'f' line(s)"),
        "{:?}",
        info.not_carried
    );
}

/// Integer fields keep their type: a PCD `label` (`U 4`, PCL's `PointXYZL`) above 2^24, which a
/// float would round, comes back exact as `U 4`, and as `uint` in PLY; an averaged (non-integer)
/// value falls back to a float.
#[test]
fn integer_fields_keep_their_type() {
    let pcd =
        b"VERSION 0.7\nFIELDS x y z label ring\nSIZE 4 4 4 4 2\nTYPE F F F U I\nCOUNT 1 1 1 1 1\n\
WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n0 0 0 16777217 -3\n1 0 0 7 12\n";
    let c = io::read_bytes(pcd, Format::Pcd).unwrap();
    assert_eq!(c.scalar("label").unwrap(), [16777217.0, 7.0]);
    for (enc, bytes) in pcd_encodings(&c) {
        let head = String::from_utf8_lossy(&bytes[..160]).to_string();
        assert!(
            head.contains("SIZE 4 4 4 4 2\nTYPE F F F U I\n"),
            "{enc:?}: {head}"
        );
        let back = io::read_bytes(&bytes, Format::Pcd).unwrap();
        assert_eq!(back.scalars, c.scalars, "{enc:?}");
    }
    let ply = io::write_bytes(&c, Format::Ply, &WriteOptions::ascii()).unwrap();
    let text = String::from_utf8_lossy(&ply).to_string();
    assert!(
        text.contains("property uint label\nproperty short ring\n"),
        "{text}"
    );
    assert!(text.contains("\n0 0 0 16777217 -3\n"), "{text}");
    let mut avg = c.clone();
    avg.set_scalar("label", vec![0.5, 7.0]).unwrap();
    let bytes = io::write_bytes(&avg, Format::Pcd, &WriteOptions::ascii()).unwrap();
    let head = String::from_utf8_lossy(&bytes[..160]).to_string();
    assert!(head.contains("TYPE F F F F I\n"), "{head}");
}
