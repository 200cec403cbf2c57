//! Point filters over a neighbour index ([`crate::index::NeighborIndex`]: a static or a growing
//! tree), as PCL and Open3D users know them: statistical outlier removal
//! (PCL `StatisticalOutlierRemoval`, Open3D `remove_statistical_outlier`) and radius outlier
//! removal (PCL `RadiusOutlierRemoval`, Open3D `remove_radius_outlier`). Each returns the
//! caller's indices of the points it keeps, ascending, and can give them as a mask; a growing
//! tree keeps exactly what a static tree over its live points keeps.
//! Voxel-grid downsampling (PCL `VoxelGrid`, Open3D `voxel_down_sample`, `voxel.rs`) needs no
//! tree: it reads the caller's buffer and gives each occupied voxel's centroid, members and
//! the member nearest the centroid.
//!
//! Both are exact (the index's exact neighbourhoods, `src/index/`) and identical for any thread
//! count (the per-point values come from an all-point table in the caller's order and are
//! reduced in index order). Points skipped at build time (non-finite, with
//! [`crate::NonFinitePolicy::Skip`]) or removed from a growing tree are **never kept** and
//! take no part in the statistics.
//! (PCL 1.13's `StatisticalOutlierRemoval` keeps NaN points in its output — it gives them a
//! mean distance of 0 — and its `RadiusOutlierRemoval` drops them; `cpp_examples/` bridges
//! the first.)

mod outliers;
mod voxel;
pub(crate) use voxel::check_leaf_count;

pub use outliers::{
    mean_distance, outlier_threshold, radius_outlier_removal, squared_deviation_sum,
    statistical_outlier_removal, Kept, RadiusOutlierOptions, StatisticalOutlierOptions,
};
pub use voxel::{voxel_grid, VoxelGrid, VoxelGridOptions};
