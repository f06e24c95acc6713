//! What every traversal shares: the traversal stack ([`Stack`]) and the check
//! that a ray can be traced at all ([`is_finite_ray`]).

use std::mem::MaybeUninit;

use glam::Vec3A;

use super::node::{ChildRef, WIDTH};
use super::sah;
use crate::geometry::ray::Ray;

/// Traversal stack size: at most `WIDTH - 1` entries per level of the tree, whose
/// depth is at most that of the binary splits it is made of: [`sah::MAX_SAH_DEPTH`]
/// SAH levels, then median splits of fewer than 2^27 triangles down to eight (24
/// levels) and exact splits of four triangles or fewer (2), within the 32 spare.
pub(super) const STACK_SIZE: usize = (WIDTH - 1) * (sah::MAX_SAH_DEPTH + 32);

/// A fixed-size traversal stack that is not zeroed on creation: traversal runs once
/// per ray, and clearing a few kilobytes each time cost more than the box tests.
pub(super) struct Stack<T: Copy> {
    items: [MaybeUninit<T>; STACK_SIZE],
    pub(super) len: usize,
}

impl<T: Copy> Stack<T> {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self {
            items: [const { MaybeUninit::uninit() }; STACK_SIZE],
            len: 0,
        }
    }

    #[inline(always)]
    pub(super) fn push(&mut self, item: T) {
        // Indexing checks the bound: a too-deep tree panics rather than corrupts.
        self.items[self.len] = MaybeUninit::new(item);
        self.len += 1;
    }

    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every slot below `len` was written by `push`.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

impl Stack<(ChildRef, f32)> {
    /// Sorts the entries from `base` up by entry distance, farthest at the bottom,
    /// so that the nearest pops first (insertion sort: at most eight entries).
    #[inline(always)]
    pub(super) fn sort_far_to_near(&mut self, base: usize) {
        for i in base + 1..self.len {
            // SAFETY: every slot below `len` was written by `push`.
            let item = unsafe { self.items[i].assume_init() };
            let mut j = i;
            while j > base && unsafe { self.items[j - 1].assume_init().1 } < item.1 {
                self.items[j] = self.items[j - 1];
                j -= 1;
            }
            self.items[j] = MaybeUninit::new(item);
        }
    }
}

/// Whether every coordinate of the ray is finite: `x · 0` is 0 for finite `x`
/// and NaN for an infinity or a NaN (one comparison of the sum, where
/// `is_finite` on both vectors cost a dozen instructions more a ray).
#[inline(always)]
pub(super) fn is_finite_ray(ray: &Ray) -> bool {
    (ray.origin * 0.0 + ray.dir * 0.0).cmpeq(Vec3A::ZERO).all()
}
