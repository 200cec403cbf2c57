//! Point-set smoothing (thesis Section 2.1.3 and 2.3).
