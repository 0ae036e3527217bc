//! Numbers in lanes: the contact law is written once, generic over [`Real`], and runs on one
//! contact at a time (`f64`) or on four at once ([`F4`]).
//!
//! Every operation of [`F4`] is the same IEEE operation lane by lane (no fused multiply-add,
//! no reordering), so a contact evaluated in a lane of four gets exactly the bits it gets
//! alone: the force loop, the walls and the measurements share one law, whichever width
//! runs it. Branches become selects: both sides are computed and one is kept, which gives
//! the same result as the branch taken (an unused side may hold an infinity or a NaN).

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A number, or a lane group of numbers, the contact law computes with.
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// One truth value per lane.
    type Mask: Copy;
    /// Every lane `x`.
    fn splat(x: f64) -> Self;
    /// Square root, lane by lane.
    fn sqrt(self) -> Self;
    /// Absolute value, lane by lane.
    fn abs(self) -> Self;
    /// Sine and cosine, lane by lane (each lane with `f64::sin_cos`).
    fn sin_cos(self) -> (Self, Self);
    /// `self < other`, lane by lane.
    fn lt(self, other: Self) -> Self::Mask;
    /// `self > other`, lane by lane.
    fn gt(self, other: Self) -> Self::Mask;
    /// `self == other`, lane by lane.
    fn eq(self, other: Self) -> Self::Mask;
    /// `self <= other`, lane by lane.
    fn le(self, other: Self) -> Self::Mask;
    /// Every lane `b`.
    fn all(b: bool) -> Self::Mask;
    /// `a && b`, lane by lane.
    fn both(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// `if mask { a } else { b }`, lane by lane.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
}

impl Real for f64 {
    type Mask = bool;
    #[inline(always)]
    fn splat(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> f64 {
        f64::abs(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (f64, f64) {
        f64::sin_cos(self)
    }
    #[inline(always)]
    fn lt(self, other: f64) -> bool {
        self < other
    }
    #[inline(always)]
    fn gt(self, other: f64) -> bool {
        self > other
    }
    #[inline(always)]
    fn eq(self, other: f64) -> bool {
        self == other
    }
    #[inline(always)]
    fn le(self, other: f64) -> bool {
        self <= other
    }
    #[inline(always)]
    fn all(b: bool) -> bool {
        b
    }
    #[inline(always)]
    fn both(a: bool, b: bool) -> bool {
        a && b
    }
    #[inline(always)]
    fn select(mask: bool, a: f64, b: f64) -> f64 {
        if mask { a } else { b }
    }
}

/// Four `f64` lanes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct F4(pub [f64; 4]);

/// Applies `f` lane by lane.
#[inline(always)]
fn lanes(f: impl Fn(usize) -> f64) -> F4 {
    F4([f(0), f(1), f(2), f(3)])
}

macro_rules! f4_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for F4 {
            type Output = F4;
            #[inline(always)]
            fn $method(self, rhs: F4) -> F4 {
                lanes(|l| self.0[l] $op rhs.0[l])
            }
        }
    };
}
f4_op!(Add, add, +);
f4_op!(Sub, sub, -);
f4_op!(Mul, mul, *);
f4_op!(Div, div, /);

impl Neg for F4 {
    type Output = F4;
    #[inline(always)]
    fn neg(self) -> F4 {
        lanes(|l| -self.0[l])
    }
}

impl Real for F4 {
    type Mask = [bool; 4];
    #[inline(always)]
    fn splat(x: f64) -> F4 {
        F4([x; 4])
    }
    #[inline(always)]
    fn sqrt(self) -> F4 {
        lanes(|l| self.0[l].sqrt())
    }
    #[inline(always)]
    fn abs(self) -> F4 {
        lanes(|l| self.0[l].abs())
    }
    #[inline(always)]
    fn sin_cos(self) -> (F4, F4) {
        let both: [(f64, f64); 4] = std::array::from_fn(|l| self.0[l].sin_cos());
        (lanes(|l| both[l].0), lanes(|l| both[l].1))
    }
    #[inline(always)]
    fn lt(self, other: F4) -> [bool; 4] {
        std::array::from_fn(|l| self.0[l] < other.0[l])
    }
    #[inline(always)]
    fn gt(self, other: F4) -> [bool; 4] {
        std::array::from_fn(|l| self.0[l] > other.0[l])
    }
    #[inline(always)]
    fn eq(self, other: F4) -> [bool; 4] {
        std::array::from_fn(|l| self.0[l] == other.0[l])
    }
    #[inline(always)]
    fn le(self, other: F4) -> [bool; 4] {
        std::array::from_fn(|l| self.0[l] <= other.0[l])
    }
    #[inline(always)]
    fn all(b: bool) -> [bool; 4] {
        [b; 4]
    }
    #[inline(always)]
    fn both(a: [bool; 4], b: [bool; 4]) -> [bool; 4] {
        std::array::from_fn(|l| a[l] && b[l])
    }
    #[inline(always)]
    fn select(mask: [bool; 4], a: F4, b: F4) -> F4 {
        lanes(|l| if mask[l] { a.0[l] } else { b.0[l] })
    }
}

/// A 3-vector of [`Real`]s (m, m/s, N, … as the quantity it holds). Its dot and cross
/// products use the operation order of `glam::DVec3`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct V3<R> {
    /// `x` component.
    pub x: R,
    /// `y` component.
    pub y: R,
    /// `z` component.
    pub z: R,
}

impl<R: Real> V3<R> {
    /// The vector `(x, y, z)`.
    #[inline(always)]
    pub fn new(x: R, y: R, z: R) -> V3<R> {
        V3 { x, y, z }
    }

    /// The zero vector.
    #[inline(always)]
    pub fn zero() -> V3<R> {
        let z = R::splat(0.0);
        V3 { x: z, y: z, z }
    }

    /// `self · o`.
    #[inline(always)]
    pub fn dot(self, o: V3<R>) -> R {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }

    /// `self × o`.
    #[inline(always)]
    pub fn cross(self, o: V3<R>) -> V3<R> {
        V3 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// `s self`.
    #[inline(always)]
    pub fn scale(self, s: R) -> V3<R> {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    /// `if mask { a } else { b }`, lane by lane.
    #[inline(always)]
    pub fn select(mask: R::Mask, a: V3<R>, b: V3<R>) -> V3<R> {
        V3 {
            x: R::select(mask, a.x, b.x),
            y: R::select(mask, a.y, b.y),
            z: R::select(mask, a.z, b.z),
        }
    }
}

impl<R: Real> Add for V3<R> {
    type Output = V3<R>;
    #[inline(always)]
    fn add(self, o: V3<R>) -> V3<R> {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<R: Real> Sub for V3<R> {
    type Output = V3<R>;
    #[inline(always)]
    fn sub(self, o: V3<R>) -> V3<R> {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl<R: Real> Neg for V3<R> {
    type Output = V3<R>;
    #[inline(always)]
    fn neg(self) -> V3<R> {
        V3::new(-self.x, -self.y, -self.z)
    }
}

impl V3<f64> {
    /// From a `glam` vector.
    #[inline(always)]
    pub fn from_glam(v: glam::DVec3) -> V3<f64> {
        V3::new(v.x, v.y, v.z)
    }

    /// To a `glam` vector.
    #[inline(always)]
    pub fn to_glam(self) -> glam::DVec3 {
        glam::DVec3::new(self.x, self.y, self.z)
    }
}

impl F4 {
    /// The four numbers `a` as lanes. With `AVX` the lanes are put together in registers
    /// (the same bits as lane by lane through memory, which makes the first use of the
    /// group wait on four stores).
    ///
    /// # Safety
    /// With `AVX`, the CPU supports AVX.
    #[inline(always)]
    pub unsafe fn from_array<const AVX: bool>(a: [f64; 4]) -> F4 {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: the caller's contract.
            return unsafe { avx::from_array(a) };
        }
        F4(a)
    }
}

impl V3<F4> {
    /// The four vectors `rows` as lanes, lane `l` from `rows[l]`. With `AVX` the rows are
    /// transposed in registers (see [`F4::from_array`]).
    ///
    /// # Safety
    /// With `AVX`, the CPU supports AVX.
    #[inline(always)]
    pub unsafe fn from_rows<const AVX: bool>(rows: [glam::DVec3; 4]) -> V3<F4> {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: the caller's contract.
            return unsafe { avx::from_rows(rows) };
        }
        let mut v = V3::<F4>::default();
        for (l, r) in rows.into_iter().enumerate() {
            v.set_lane(l, r);
        }
        v
    }

    /// Lane `l` of each component.
    #[inline(always)]
    pub fn lane(&self, l: usize) -> glam::DVec3 {
        glam::DVec3::new(self.x.0[l], self.y.0[l], self.z.0[l])
    }

    /// Sets lane `l` of each component.
    #[inline(always)]
    pub fn set_lane(&mut self, l: usize, v: glam::DVec3) {
        self.x.0[l] = v.x;
        self.y.0[l] = v.y;
        self.z.0[l] = v.z;
    }
}

/// Lane groups put together in AVX registers.
#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{F4, V3};
    use std::arch::x86_64::{
        __m256d, _mm_set_sd, _mm_setr_pd, _mm256_castpd128_pd256, _mm256_insertf128_pd,
        _mm256_permute2f128_pd, _mm256_setr_pd, _mm256_unpackhi_pd, _mm256_unpacklo_pd,
    };

    /// The lanes of a register.
    #[inline(always)]
    fn lanes(v: __m256d) -> F4 {
        // SAFETY: both are four `f64`s, `F4` with `__m256d`'s alignment.
        unsafe { std::mem::transmute::<__m256d, F4>(v) }
    }

    /// See [`F4::from_array`].
    #[target_feature(enable = "avx")]
    #[inline]
    pub(super) fn from_array(a: [f64; 4]) -> F4 {
        lanes(_mm256_setr_pd(a[0], a[1], a[2], a[3]))
    }

    /// See [`V3::from_rows`]: each row `(x, y, z, 0)`, then a 4×4 transpose of which the
    /// fourth row is dropped.
    #[target_feature(enable = "avx")]
    #[inline]
    pub(super) fn from_rows(rows: [glam::DVec3; 4]) -> V3<F4> {
        let row = |v: glam::DVec3| {
            _mm256_insertf128_pd::<1>(
                _mm256_castpd128_pd256(_mm_setr_pd(v.x, v.y)),
                _mm_set_sd(v.z),
            )
        };
        let (r0, r1, r2, r3) = (row(rows[0]), row(rows[1]), row(rows[2]), row(rows[3]));
        // (x0, x1, z0, z1), (y0, y1, 0, 0), (x2, x3, z2, z3), (y2, y3, 0, 0)
        let (t0, t1) = (_mm256_unpacklo_pd(r0, r1), _mm256_unpackhi_pd(r0, r1));
        let (t2, t3) = (_mm256_unpacklo_pd(r2, r3), _mm256_unpackhi_pd(r2, r3));
        V3 {
            x: lanes(_mm256_permute2f128_pd::<0x20>(t0, t2)),
            y: lanes(_mm256_permute2f128_pd::<0x20>(t1, t3)),
            z: lanes(_mm256_permute2f128_pd::<0x31>(t0, t2)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_groups_put_together_in_registers_hold_the_rows() {
        let rows = [
            glam::DVec3::new(1.0, -2.0, 3.0),
            glam::DVec3::new(-0.0, 5.5, f64::INFINITY),
            glam::DVec3::new(7.0, f64::MIN_POSITIVE, -9.0),
            glam::DVec3::new(1e300, 11.0, -1e-300),
        ];
        let numbers = [0.5, -0.0, 3.0e-7, -8.0];
        // SAFETY: without AVX the lanes are set one by one; with it only where the CPU
        // has it.
        let plain = unsafe {
            (
                V3::from_rows::<false>(rows),
                F4::from_array::<false>(numbers),
            )
        };
        for (l, r) in rows.iter().enumerate() {
            assert_eq!(plain.0.lane(l), *r);
        }
        assert_eq!(plain.1.0, numbers);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX, checked just above.
            let avx = unsafe { (V3::from_rows::<true>(rows), F4::from_array::<true>(numbers)) };
            for (l, r) in rows.iter().enumerate() {
                assert_eq!(
                    avx.0.lane(l).to_array().map(f64::to_bits),
                    r.to_array().map(f64::to_bits)
                );
            }
            assert_eq!(avx.1.0.map(f64::to_bits), numbers.map(f64::to_bits));
        }
    }

    #[test]
    fn four_lanes_give_the_bits_of_one() {
        let a = [1.0e-3, -2.5, 3.0e7, 0.1];
        let b = [7.0, 1.0e-9, -0.3, 0.1];
        let (fa, fb) = (F4(a), F4(b));
        for l in 0..4 {
            assert_eq!(
                (fa * fb + fa / fb - fb).0[l],
                a[l] * b[l] + a[l] / b[l] - b[l]
            );
            assert_eq!(fa.abs().sqrt().0[l], a[l].abs().sqrt());
            assert_eq!(F4::select(fa.lt(fb), fa, fb).0[l], a[l].min(b[l]));
        }
        let u = V3::new(F4(a), F4(b), F4([0.5; 4]));
        let v = V3::new(F4(b), F4([2.0; 4]), F4(a));
        for l in 0..4 {
            let (gu, gv) = (u.lane(l), v.lane(l));
            assert_eq!(u.cross(v).lane(l), gu.cross(gv));
            assert_eq!(u.dot(v).0[l], gu.dot(gv));
        }
    }
}
