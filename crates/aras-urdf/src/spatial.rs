//! Three-vectors and 3 × 3 matrices as plain arrays, generic over the
//! number type (f64 or dual numbers). Matrices are row-major: `m[r][c]`.

use num_dual::DualNum;

/// A 3-vector.
pub(crate) type V3<T> = [T; 3];
/// A 3 × 3 matrix, row-major.
pub(crate) type M3<T> = [[T; 3]; 3];

/// The number types the model evaluates in: `f64` and the dual numbers of
/// `num-dual` over `f64`.
pub trait Scalar: DualNum<Primitive = f64> + Copy {}
impl<T: DualNum<Primitive = f64> + Copy> Scalar for T {}

#[inline(always)]
pub(crate) fn zero<T: Scalar>() -> T {
    T::from(0.0)
}

#[inline(always)]
pub(crate) fn zero3<T: Scalar>() -> V3<T> {
    [zero(); 3]
}

#[inline(always)]
pub(crate) fn cross<T: Scalar>(a: V3<T>, b: V3<T>) -> V3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a × b` with a constant `a`.
#[inline(always)]
pub(crate) fn cross_c<T: Scalar>(a: V3<f64>, b: V3<T>) -> V3<T> {
    [
        b[2] * a[1] - b[1] * a[2],
        b[0] * a[2] - b[2] * a[0],
        b[1] * a[0] - b[0] * a[1],
    ]
}

#[inline(always)]
pub(crate) fn dot<T: Scalar>(a: V3<T>, b: V3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a · b` with a constant `a`.
#[inline(always)]
pub(crate) fn dot_c<T: Scalar>(a: V3<f64>, b: V3<T>) -> T {
    b[0] * a[0] + b[1] * a[1] + b[2] * a[2]
}

#[inline(always)]
pub(crate) fn add<T: Scalar>(a: V3<T>, b: V3<T>) -> V3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `s · a` with a constant direction `a`.
#[inline(always)]
pub(crate) fn scale_c<T: Scalar>(a: V3<f64>, s: T) -> V3<T> {
    [s * a[0], s * a[1], s * a[2]]
}

/// `s v` with a constant `s`.
#[inline(always)]
pub(crate) fn scale<T: Scalar>(v: V3<T>, s: f64) -> V3<T> {
    [v[0] * s, v[1] * s, v[2] * s]
}

#[inline(always)]
pub(crate) fn lift<T: Scalar>(a: V3<f64>) -> V3<T> {
    [T::from(a[0]), T::from(a[1]), T::from(a[2])]
}

/// `m v`.
#[inline(always)]
pub(crate) fn mul<T: Scalar>(m: &M3<T>, v: V3<T>) -> V3<T> {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// `mᵀ v`.
#[inline(always)]
pub(crate) fn mul_t<T: Scalar>(m: &M3<T>, v: V3<T>) -> V3<T> {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}

/// `a b`.
pub(crate) fn mat_mul<T: Scalar>(a: &M3<T>, b: &M3<T>) -> M3<T> {
    let mut c = [[zero(); 3]; 3];
    for r in 0..3 {
        for k in 0..3 {
            c[r][k] = a[r][0] * b[0][k] + a[r][1] * b[1][k] + a[r][2] * b[2][k];
        }
    }
    c
}

/// The transpose.
pub(crate) fn transpose(a: &M3<f64>) -> M3<f64> {
    let mut t = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            t[r][c] = a[c][r];
        }
    }
    t
}

pub(crate) const IDENTITY: M3<f64> = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The rotation of URDF's `rpy` (fixed axes x, then y, then z:
/// `Rz(yaw) Ry(pitch) Rx(roll)`).
pub(crate) fn rpy_matrix(rpy: V3<f64>) -> M3<f64> {
    let (sr, cr) = rpy[0].sin_cos();
    let (sp, cp) = rpy[1].sin_cos();
    let (sy, cy) = rpy[2].sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// `[a]×`, the matrix of `a × ·`.
pub(crate) fn skew(a: V3<f64>) -> M3<f64> {
    [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]]
}
