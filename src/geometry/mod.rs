//! Geometry: rays, the watertight ray–triangle test and the eight-wide BVH that
//! answers the scene's ray queries.

pub mod bvh;
pub mod ray;
pub mod triangle;
