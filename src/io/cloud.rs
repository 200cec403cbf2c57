//! The cloud read from or written to a file: positions, normals, named scalar fields, the grid
//! of an organized scan, the colour conventions of the formats, and the precision its values
//! are stored in.

use crate::error::{NbhdError, Result as NbhdResult};
use crate::points::PointsView;

use super::meta::Metadata;
use super::value::Ty;

/// Width of the stored floating-point values (coordinates, normals, scalar fields).
///
/// The default is [`Single`](Precision::Single), because that is what other tools load:
/// PCL's `PointXYZ`, `PointNormal`, `PointXYZRGB` are `float` types and its loaders match a
/// field only if its type is `float` (a `double` x is "Failed to find match for field 'x'"
/// and the point stays 0); MeshLab and CloudCompare read both.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Precision {
    /// 32-bit `float` (PLY `float`, PCD `F 4`): what PCL's point types hold, about 7 digits.
    #[default]
    Single,
    /// 64-bit `double` (PLY `double`, PCD `F 8`): exact for nbhd's `f64` values.
    Double,
    /// As the cloud was read ([`PointCloud::source_precision`]): double if the file held
    /// the coordinates more precisely than a `float` does, single otherwise.
    Keep,
}

impl Precision {
    /// Whether `cloud` is written in single precision.
    pub fn is_single_for(self, cloud: &PointCloud) -> bool {
        match self {
            Precision::Single => true,
            Precision::Double => false,
            Precision::Keep => cloud.source_precision != Some(Precision::Double),
        }
    }

    /// The precision a file's coordinate type holds.
    pub(crate) fn of_type(ty: Ty) -> Precision {
        match ty {
            Ty::F64 | Ty::I32 | Ty::U32 | Ty::I64 | Ty::U64 => Precision::Double,
            _ => Precision::Single,
        }
    }

    /// The precision text coordinates need: double if one is not exactly a `float`.
    pub(crate) fn of_text(positions: &[[f64; 3]]) -> Precision {
        let exact = |v: f64| !v.is_finite() || v as f32 as f64 == v;
        if positions.iter().all(|p| p.iter().all(|&v| exact(v))) {
            Precision::Single
        } else {
            Precision::Double
        }
    }
}

/// A named per-point scalar, e.g. `curvature` or `intensity`.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarField {
    /// Name as in the file (`curvature`, `intensity`, `rgb`, ...).
    pub name: String,
    /// One value per point.
    pub values: Vec<f64>,
}

/// Width and height of an organized cloud (a depth image: point `i` is pixel
/// `(i % width, i / width)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

/// Axis-aligned bounding box of the finite points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest x, y, z.
    pub min: [f64; 3],
    /// Largest x, y, z.
    pub max: [f64; 3],
}

impl Aabb {
    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        (0..3)
            .map(|j| (self.max[j] - self.min[j]).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// A point cloud as read from or written to a file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    /// Positions, in file order; non-finite ones kept.
    pub positions: Vec<[f64; 3]>,
    /// Per-point normals, if the file has them (`nx ny nz` or `normal_x ...`).
    pub normals: Option<Vec<[f64; 3]>>,
    /// Other per-point values, in file order.
    pub scalars: Vec<ScalarField>,
    /// Width and height of an organized cloud (PCD with `HEIGHT` > 1).
    pub grid: Option<Grid>,
    /// How precisely the file read held the coordinates: [`Precision::Double`] for PLY
    /// `double`/`int`/`uint`, PCD `F 8`/`I 4`/`U 4`/64-bit, LAS (scaled 32-bit integers), and
    /// text with a coordinate that a `float` does not hold exactly; [`Precision::Single`]
    /// otherwise; `None` for a cloud made in memory. [`Precision::Keep`] writes by it.
    pub source_precision: Option<Precision>,
    /// What the file said about the cloud as a whole (PCD viewpoint, header comments, the LAS
    /// header), written back by the writer of the same format.
    pub metadata: Metadata,
}

impl PointCloud {
    /// A cloud of positions only.
    pub fn from_positions(positions: Vec<[f64; 3]>) -> Self {
        Self {
            positions,
            ..Self::default()
        }
    }

    /// Number of points (non-finite ones included).
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// `true` if there are no points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Sets the normals. Errors: [`NbhdError::BufferTooSmall`] if there is not one per point.
    pub fn set_normals(&mut self, normals: Vec<[f64; 3]>) -> NbhdResult<()> {
        if normals.len() != self.len() {
            return Err(NbhdError::BufferTooSmall {
                what: "normals (points)",
                len: normals.len(),
                needed: self.len(),
            });
        }
        self.normals = Some(normals);
        Ok(())
    }

    /// Adds a scalar field, replacing one of the same name. Errors:
    /// [`NbhdError::BufferTooSmall`] if there is not one value per point.
    pub fn set_scalar(&mut self, name: &str, values: Vec<f64>) -> NbhdResult<()> {
        if values.len() != self.len() {
            return Err(NbhdError::BufferTooSmall {
                what: "scalar values (points)",
                len: values.len(),
                needed: self.len(),
            });
        }
        match self.scalars.iter_mut().find(|s| s.name == name) {
            Some(s) => s.values = values,
            None => self.scalars.push(ScalarField {
                name: name.to_string(),
                values,
            }),
        }
        Ok(())
    }

    /// The values of the scalar field `name`.
    pub fn scalar(&self, name: &str) -> Option<&[f64]> {
        self.scalars
            .iter()
            .find(|s| s.name == name)
            .map(|s| s.values.as_slice())
    }

    /// Per-point colours, if the cloud has them: a packed `rgb`/`rgba` field (as PCL writes
    /// them) or `red`, `green`, `blue` fields (as PLY files have them, 0..255; 16-bit ones,
    /// as LAS has them, by their high byte).
    pub fn colors(&self) -> Option<Vec<[u8; 3]>> {
        if let Some(v) = self.packed_color_field() {
            return Some(
                v.iter()
                    .map(|&c| {
                        let c = if c.is_finite() { c as u32 } else { 0 };
                        [(c >> 16) as u8, (c >> 8) as u8, c as u8]
                    })
                    .collect(),
            );
        }
        let (r, g, b) = (
            self.scalar("red")?,
            self.scalar("green")?,
            self.scalar("blue")?,
        );
        // 16-bit channels (LAS, PLY `ushort`): any value above 255 makes them all 16-bit,
        // taken by their high byte (the LAS convention).
        let wide = [r, g, b].iter().any(|c| c.iter().any(|&v| v > 255.0));
        let ch = |v: f64| {
            let v = if wide { v / 256.0 } else { v };
            v.clamp(0.0, 255.0) as u8
        };
        Some(
            (0..self.len())
                .map(|i| [ch(r[i]), ch(g[i]), ch(b[i])])
                .collect(),
        )
    }

    /// The packed colour field (`rgb`, else `rgba`) if it holds 32-bit unsigned integers.
    pub(super) fn packed_color_field(&self) -> Option<&[f64]> {
        ["rgb", "rgba"]
            .iter()
            .filter_map(|n| self.scalar(n))
            .find(|v| {
                v.iter()
                    .all(|&x| (0.0..=u32::MAX as f64).contains(&x) && x.fract() == 0.0)
            })
    }

    /// Number of points with a NaN or infinite coordinate.
    pub fn non_finite_count(&self) -> usize {
        self.positions
            .iter()
            .filter(|p| !p.iter().all(|c| c.is_finite()))
            .count()
    }

    /// Bounding box of the finite points, `None` if there is none.
    pub fn bounding_box(&self) -> Option<Aabb> {
        let mut it = self
            .positions
            .iter()
            .filter(|p| p.iter().all(|c| c.is_finite()));
        let first = *it.next()?;
        let mut b = Aabb {
            min: first,
            max: first,
        };
        for p in it {
            for (j, &c) in p.iter().enumerate() {
                b.min[j] = b.min[j].min(c);
                b.max[j] = b.max[j].max(c);
            }
        }
        Some(b)
    }

    /// Names of the per-point fields: `x y z`, then `nx ny nz` if there are normals, then the
    /// scalar fields.
    pub fn field_names(&self) -> Vec<String> {
        let mut v: Vec<String> = ["x", "y", "z"].iter().map(|s| s.to_string()).collect();
        if self.normals.is_some() {
            v.extend(["nx", "ny", "nz"].iter().map(|s| s.to_string()));
        }
        v.extend(self.scalars.iter().map(|s| s.name.clone()));
        v
    }

    /// The positions as a [`PointsView`] for the trees (3 dimensions, `f64`).
    /// Errors: [`NbhdError::EmptyInput`] for an empty cloud.
    pub fn view(&self) -> NbhdResult<PointsView<'_>> {
        PointsView::from_rows(&self.positions)
    }

    /// Checks that normals and scalar fields have one entry per point and that the grid,
    /// if any, covers the points.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let n = self.len();
        if let Some(nr) = &self.normals {
            if nr.len() != n {
                return Err(format!("{n} positions but {} normals", nr.len()));
            }
        }
        for s in &self.scalars {
            if s.values.len() != n {
                return Err(format!(
                    "{n} positions but {} values of scalar field '{}'",
                    s.values.len(),
                    s.name
                ));
            }
        }
        if let Some(g) = self.grid {
            if g.width * g.height != n {
                return Err(format!(
                    "grid {} x {} does not hold {n} points",
                    g.width, g.height
                ));
            }
        }
        Ok(())
    }
}

/// `rgb` and `rgba` fields hold a colour packed as `0xAARRGGBB`: PCL stores it as the bits of
/// a float (`F 4`) or as `U 4`. nbhd keeps the integer and writes it as a 32-bit unsigned
/// integer, which is bit-identical to PCL's float.
pub(crate) fn is_packed_name(name: &str) -> bool {
    name == "rgb" || name == "rgba"
}
