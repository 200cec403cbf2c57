//! What Chapter 8 measures: its three geometries at their sizes (Fig. 8.1, 8.2), the tree
//! variants of Fig. 8.8 and the thesis' own figures to set beside ours.

use nbhd::shapes::{
    Catenoid, CylinderPlane, Shape, Torus, COSTA_SIZES, CYLINDER_SIZES, TORUS_SIZES,
};
use nbhd::{MedianAlgorithm, PivotPolicy};

/// A geometry of Fig. 8.1 at its three sizes.
pub(super) struct Geometry {
    pub name: &'static str,
    pub shape: Box<dyn Shape>,
    pub sizes: [usize; 3],
}

/// Costa (here a catenoid), Cylinder and Torus, in this order.
pub(super) fn geometries() -> Vec<Geometry> {
    vec![
        Geometry {
            name: "Costa (catenoid)",
            shape: Box::new(Catenoid::new(1.0, 1.2)),
            sizes: COSTA_SIZES,
        },
        Geometry {
            name: "Cylinder",
            shape: Box::new(CylinderPlane::new(0.5, 2.0)),
            sizes: CYLINDER_SIZES,
        },
        Geometry {
            name: "Torus",
            shape: Box::new(Torus::new(1.0, 0.35)),
            sizes: TORUS_SIZES,
        },
    ]
}

/// The build variants of Fig. 8.8 (first five) and the other policies.
pub(super) const VARIANTS: [(&str, PivotPolicy, MedianAlgorithm); 8] = [
    (
        "Sorting",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::Presorted,
    ),
    (
        "Median (Sorting)",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::Sort,
    ),
    (
        "Median (Linear Det.)",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::MedianOfMedians,
    ),
    (
        "Median (Floyd-Rivest)",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::FloydRivest,
    ),
    (
        "Closest to Middle",
        PivotPolicy::ClosestToMiddle,
        MedianAlgorithm::FloydRivest,
    ),
    (
        "Median (Quickselect)",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::Quickselect,
    ),
    (
        "Spread median",
        PivotPolicy::SpreadMedian,
        MedianAlgorithm::FloydRivest,
    ),
    (
        "Sliding midpoint",
        PivotPolicy::SlidingMidpoint,
        MedianAlgorithm::FloydRivest,
    ),
];

/// Thesis' Fig. 8.8 medians in ms (Sorting, Median (Sorting), Median (Linear Det.),
/// Median (Floyd-Rivest), Closest to Middle) per geometry and size.
pub(super) const THESIS_BUILD_MS: [[[f64; 3]; 5]; 3] = [
    [
        [8.0, 61.0, 326.0],
        [11.0, 89.0, 496.0],
        [15.0, 119.0, 629.0],
        [5.0, 37.0, 198.0],
        [5.0, 110.0, 2046.0],
    ],
    [
        [10.0, 76.0, 353.0],
        [13.0, 122.0, 586.0],
        [19.0, 155.0, 733.0],
        [6.0, 46.0, 201.0],
        [12.0, 108.0, 498.0],
    ],
    [
        [6.0, 32.0, 160.0],
        [8.0, 50.0, 261.0],
        [14.0, 76.0, 377.0],
        [5.0, 23.0, 106.0],
        [4.0, 70.0, 1089.0],
    ],
];

/// Thesis' Fig. 8.7 depths (balanced, closest to middle) of Cylinder and Torus.
pub(super) const THESIS_DEPTH: [Option<[[usize; 3]; 2]>; 3] = [
    None,
    Some([[12, 14, 16], [287, 694, 2162]]),
    Some([[12, 14, 16], [238, 1373, 5453]]),
];
