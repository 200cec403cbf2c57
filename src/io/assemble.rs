//! The readers' shared code: from a file's named columns to a [`PointCloud`] (which column is a
//! coordinate, a normal component or a scalar field), built point by point.

use super::cloud::{PointCloud, ScalarField};

/// Collects per-point columns into a cloud: `dest` says where each column goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Dest {
    Pos(usize),
    Normal(usize),
    Scalar(usize),
    Skip,
}

/// Maps property/field names to destinations; returns them with the scalar names.
/// Errors (as a message) if x, y or z is missing.
pub(crate) fn assign_columns(
    names: &[String],
) -> std::result::Result<(Vec<Dest>, Vec<String>, bool), String> {
    let mut dest = Vec::with_capacity(names.len());
    let mut scalars = Vec::new();
    let mut found = [false; 6];
    for name in names {
        let d = match name.as_str() {
            "x" => Dest::Pos(0),
            "y" => Dest::Pos(1),
            "z" => Dest::Pos(2),
            "nx" | "normal_x" => Dest::Normal(0),
            "ny" | "normal_y" => Dest::Normal(1),
            "nz" | "normal_z" => Dest::Normal(2),
            "_" => Dest::Skip,
            _ => {
                scalars.push(name.clone());
                Dest::Scalar(scalars.len() - 1)
            }
        };
        match d {
            Dest::Pos(j) | Dest::Normal(j) => {
                let k = if matches!(d, Dest::Pos(_)) { j } else { 3 + j };
                if found[k] {
                    scalars.push(name.clone());
                    dest.push(Dest::Scalar(scalars.len() - 1));
                    continue;
                }
                found[k] = true;
            }
            _ => {}
        }
        dest.push(d);
    }
    if let Some(j) = (0..3).find(|&j| !found[j]) {
        return Err(format!(
            "no '{}' field: nbhd needs x, y and z per point",
            ["x", "y", "z"][j]
        ));
    }
    let normals = found[3] && found[4] && found[5];
    if !normals {
        // A partial normal is kept as scalars.
        for (d, name) in dest.iter_mut().zip(names) {
            if matches!(d, Dest::Normal(_)) {
                scalars.push(name.clone());
                *d = Dest::Scalar(scalars.len() - 1);
            }
        }
    }
    Ok((dest, scalars, normals))
}

/// Most points reserved from a file's declared count before they are read: the readers check
/// counts against the bytes left, and this bounds what a hint can allocate in any case.
pub(crate) const MAX_RESERVE: usize = 1 << 20;

/// Builds a cloud point by point from column values.
pub(crate) struct Builder {
    dest: Vec<Dest>,
    cloud: PointCloud,
    normals: Vec<[f64; 3]>,
    has_normals: bool,
}

impl Builder {
    /// `n` is the number of points the file declares: a hint only, never trusted for more
    /// than [`MAX_RESERVE`] points (the vectors grow as points are pushed).
    pub fn new(dest: Vec<Dest>, scalar_names: Vec<String>, has_normals: bool, n: usize) -> Self {
        let n = n.min(MAX_RESERVE);
        let scalars = scalar_names
            .into_iter()
            .map(|name| ScalarField {
                name,
                values: Vec::with_capacity(n),
            })
            .collect();
        Self {
            dest,
            cloud: PointCloud {
                positions: Vec::with_capacity(n),
                normals: None,
                scalars,
                grid: None,
                source_precision: None,
                metadata: Default::default(),
            },
            normals: Vec::with_capacity(if has_normals { n } else { 0 }),
            has_normals,
        }
    }

    /// Adds a point from its column values (one per destination).
    pub fn push(&mut self, values: impl Iterator<Item = f64>) {
        let mut p = [0.0; 3];
        let mut nr = [0.0; 3];
        for (d, v) in self.dest.iter().zip(values) {
            match *d {
                Dest::Pos(j) => p[j] = v,
                Dest::Normal(j) => nr[j] = v,
                Dest::Scalar(s) => self.cloud.scalars[s].values.push(v),
                Dest::Skip => {}
            }
        }
        self.cloud.positions.push(p);
        if self.has_normals {
            self.normals.push(nr);
        }
    }

    pub fn finish(mut self) -> PointCloud {
        if self.has_normals {
            self.cloud.normals = Some(self.normals);
        }
        self.cloud
    }
}
