//! An eight-wide bounding volume hierarchy over triangles.
//!
//! Built top down with binned SAH (modules `sah` and `build`): every node holds
//! up to eight children whose boxes are tested together (`node`: AVX2 where the
//! CPU has it), with leaves of one or two packets of four triangles in
//! structure-of-arrays layout (`packet`; a leaf of two is tested in one AVX2
//! pass, `ray8::pair_closest`). Closest-hit traversal visits children
//! nearest first and skips any whose box starts beyond the closest hit so far;
//! any-hit traversal stops at the first hit.
//!
//! The tree ([`Bvh`], its cache bytes and soundness check) is in `tree`, one
//! ray's traversal in `single`, the stack every traversal uses in `walk`; the
//! packet and stream queries (`ray4`, `ray8`, `single8`, `stream`) are methods
//! of [`Bvh`] in files of their own.

mod build;
mod node;
mod packet;
mod ray4;
mod ray8;
mod sah;
mod single;
mod single8;
mod stream;
mod tree;
mod walk;

#[cfg(test)]
mod tests;

pub use single::brute_force;
#[cfg(target_arch = "x86_64")]
pub(crate) use single8::Singles8;
pub use stream::IN_FLIGHT;
pub use tree::Bvh;
