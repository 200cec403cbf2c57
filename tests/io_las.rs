//! LAS and LAZ through `nbhd::io`: files written by laspy (tests/data/las, made by
//! tests/data/las/make_las.py) read to the values laspy holds, round trips through nbhd's
//! writer, and nbhd's files read back by laspy itself when it is installed.
#![cfg(feature = "las")]

use nbhd::io::{self, Encoding, Format, IoErrorKind, PointCloud, WriteOptions};
use std::path::PathBuf;

fn las_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/las")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("nbhd-las-test-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// Rows of numbers of a reference file.
fn reference(name: &str) -> Vec<Vec<f64>> {
    std::fs::read_to_string(las_dir().join(name))
        .unwrap()
        .lines()
        .map(|l| l.split(' ').map(|t| t.parse().unwrap()).collect())
        .collect()
}

fn check_against_reference(c: &PointCloud, rows: &[Vec<f64>], colour: bool, what: &str) {
    assert_eq!(c.len(), rows.len(), "{what}");
    let colors = c.colors();
    assert_eq!(colors.is_some(), colour, "{what}");
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(c.positions[i], [r[0], r[1], r[2]], "{what}: point {i}");
        assert_eq!(c.scalar("intensity").unwrap()[i], r[3], "{what}: point {i}");
        assert_eq!(c.scalar("classification").unwrap()[i], r[4], "{what}: {i}");
        if let Some(col) = &colors {
            // 16-bit colours come out as their high byte.
            let want = [r[5], r[6], r[7]].map(|v| (v as u32 >> 8) as u8);
            assert_eq!(col[i], want, "{what}: colour {i}");
        }
    }
}

#[test]
fn reads_laspy_las_and_laz_to_laspys_values() {
    let rows = reference("small.ref.txt");
    for name in ["small.las", "small.laz"] {
        let (c, format) = io::read_as(las_dir().join(name), None).unwrap();
        assert_eq!(format, Format::Las);
        check_against_reference(&c, &rows, true, name);
        assert_eq!(c.source_precision, Some(io::Precision::Double));
    }
    let c = io::read(las_dir().join("small_fmt0.las")).unwrap();
    check_against_reference(&c, &reference("small_fmt0.ref.txt"), false, "small_fmt0");
    assert_eq!(
        c.field_names(),
        ["x", "y", "z", "intensity", "classification"]
    );
}

#[test]
fn round_trip_through_nbhds_las_and_laz() {
    let c = io::read(las_dir().join("small.las")).unwrap();
    for name in ["rt.las", "rt.laz"] {
        let path = tmp(name);
        io::write(&path, &c, &WriteOptions::default()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.starts_with(b"LASF"));
        let back = io::read(&path).unwrap();
        assert_eq!(back.len(), c.len());
        // 50 m of extent: steps of 1e-7, so at most half of that off (and float rounding).
        for (p, q) in c.positions.iter().zip(&back.positions) {
            for j in 0..3 {
                assert!((p[j] - q[j]).abs() <= 0.6e-7, "{name}: {p:?} vs {q:?}");
            }
        }
        for f in ["intensity", "classification"] {
            assert_eq!(back.scalar(f), c.scalar(f), "{name}: {f}");
        }
        assert_eq!(back.colors(), c.colors(), "{name}");
    }
    // The in-memory writer: LAZ when asked for compressed, and smaller.
    let las = io::write_bytes(&c, Format::Las, &WriteOptions::default()).unwrap();
    let laz = io::write_bytes(
        &c,
        Format::Las,
        &WriteOptions {
            encoding: Some(Encoding::BinaryCompressed),
            ..WriteOptions::default()
        },
    )
    .unwrap();
    assert!(
        laz.len() < las.len(),
        "LAZ {} vs LAS {}",
        laz.len(),
        las.len()
    );
    assert_eq!(io::read_bytes(&laz, Format::Las).unwrap().len(), 300);
}

#[test]
fn what_las_cannot_hold_is_named_or_refused() {
    let mut c = PointCloud::from_positions(vec![[0.0, 1.0, 2.0], [1.0, 1.0, 1.0]]);
    c.set_normals(vec![[0.0, 0.0, 1.0]; 2]).unwrap();
    c.set_scalar("curvature", vec![0.1, 0.2]).unwrap();
    c.set_scalar("intensity", vec![3.0, 4.0]).unwrap();
    c.set_scalar("classification", vec![2.0, 40.0]).unwrap();
    assert_eq!(
        io::not_written(&c, Format::Las),
        ["normals", "curvature", "classification"]
    );
    assert!(io::not_written(&c, Format::Ply).is_empty());
    c.positions[1][2] = f64::NAN;
    let path = tmp("nan.las");
    let e = io::write(&path, &c, &WriteOptions::default()).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::InvalidCloud(_)), "{e}");
    assert!(e.to_string().contains("point 1"), "{e}");
    assert!(!path.exists());
}

#[test]
fn hostile_las_headers_are_errors() {
    let good = std::fs::read(las_dir().join("small_fmt0.las")).unwrap();
    // Truncated in the points, and cut in the header.
    for cut in [good.len() - 7, 100, 4] {
        let e = io::read_bytes(&good[..cut], Format::Las).unwrap_err();
        assert!(matches!(e.kind, IoErrorKind::Malformed(_)), "{cut}: {e}");
    }
    // A point count of 2^64 - 1 (LAS 1.4's 64-bit count at byte 247) and 2^32 - 1 (legacy
    // count at byte 107).
    let mut b = good.clone();
    b[247..255].copy_from_slice(&u64::MAX.to_le_bytes());
    b[107..111].copy_from_slice(&0u32.to_le_bytes());
    let e = io::read_bytes(&b, Format::Las).unwrap_err();
    println!("{e}");
    let mut b = good.clone();
    b[107..111].copy_from_slice(&u32::MAX.to_le_bytes());
    b[247..255].copy_from_slice(&(u32::MAX as u64).to_le_bytes());
    let e = io::read_bytes(&b, Format::Las).unwrap_err();
    println!("{e}");
    // Found by the fuzzer (read_las): a point count whose byte size overflows, which the las
    // crate multiplies unchecked; refused before it is handed the file.
    let crash = std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/fuzz-regressions/las/mul-overflow-offset-to-end.las"),
    )
    .unwrap();
    let e = io::read_bytes(&crash, Format::Las).unwrap_err();
    assert!(e.to_string().contains("overflows"), "{e}");
    // Also found by the fuzzer: a LAZ chunk table declaring ~4e9 chunks, which the laz crate
    // reserved for (a 64 GiB allocation: abort).
    let crash = std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/fuzz-regressions/las/laz-chunk-count.laz"),
    )
    .unwrap();
    let e = io::read_bytes(&crash, Format::Las).unwrap_err();
    assert!(e.to_string().contains("chunk table declares"), "{e}");
    // And a LAZ item list the laz crate panics on (an `expect`): the panic is caught and
    // returned as an error.
    let crash = std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/fuzz-regressions/las/laz-missing-item.laz"),
    )
    .unwrap();
    let e = io::read_bytes(&crash, Format::Las).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::Malformed(_)), "{e}");
    // And an extended VLR declaring about 2e16 bytes of data, which the las crate resized its
    // buffer to before reading (an abort).
    let crash = std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/fuzz-regressions/las/evlr-length.las"),
    )
    .unwrap();
    let e = io::read_bytes(&crash, Format::Las).unwrap_err();
    assert!(e.to_string().contains("extended VLR"), "{e}");
}

/// nbhd's LAS and LAZ read by laspy, the reference implementation the files came from.
#[test]
fn laspy_reads_nbhds_files() {
    let probe = std::process::Command::new("python3")
        .args(["-c", "import laspy, lazrs"])
        .output();
    if !matches!(&probe, Ok(o) if o.status.success()) {
        assert!(
            std::env::var_os("NBHD_REQUIRE_LASPY").is_none(),
            "NBHD_REQUIRE_LASPY is set but python3 -c 'import laspy, lazrs' fails"
        );
        println!("NOTE: laspy with lazrs is not installed; laspy_reads_nbhds_files skipped");
        return;
    }
    let c = io::read(las_dir().join("small.las")).unwrap();
    for name in ["by-nbhd.las", "by-nbhd.laz"] {
        let path = tmp(name);
        io::write(&path, &c, &WriteOptions::default()).unwrap();
        let script = "import sys, laspy\n\
                      l = laspy.read(sys.argv[1])\n\
                      for i in range(len(l.x)):\n\
                      \x20   print(repr(float(l.x[i])), repr(float(l.y[i])), repr(float(l.z[i])), \
                      int(l.intensity[i]), int(l.classification[i]), int(l.red[i]), \
                      int(l.green[i]), int(l.blue[i]))\n";
        let o = std::process::Command::new("python3")
            .args(["-c", script, path.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = String::from_utf8(o.stdout).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .map(|l| l.split(' ').map(|t| t.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), c.len(), "{name}");
        let colors = c.colors().unwrap();
        for (i, r) in rows.iter().enumerate() {
            for (got, want) in r.iter().zip(c.positions[i]) {
                assert!((got - want).abs() <= 0.6e-7, "{name}: {i}");
            }
            assert_eq!(r[3], c.scalar("intensity").unwrap()[i]);
            assert_eq!(r[4], c.scalar("classification").unwrap()[i]);
            // 8-bit channels written as 16-bit (x 257).
            for k in 0..3 {
                assert_eq!(r[5 + k], colors[i][k] as f64 * 257.0, "{name}: {i}");
            }
        }
    }
}
