//! [`Vector<F>`]: a 3-vector in frame `F`.

use std::fmt;
use std::marker::PhantomData;
use std::ops::{Add, AddAssign, Div, Index, Mul, Neg, Sub, SubAssign};

use nalgebra::Vector3;

/// A 3-vector in frame `F` ([`Frd`](super::Frd) or [`Ned`](super::Ned)).
/// Arithmetic only between vectors of the same frame; to and from nalgebra only
/// by name.
pub struct Vector<F> {
    v: Vector3<f64>,
    frame: PhantomData<F>,
}

impl<F> Vector<F> {
    /// The vector `(x, y, z)` in frame `F`.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self::from_nalgebra(Vector3::new(x, y, z))
    }

    /// The zero vector.
    pub fn zeros() -> Self {
        Self::from_nalgebra(Vector3::zeros())
    }

    /// The nalgebra vector `v`, declared to be in frame `F`.
    pub const fn from_nalgebra(v: Vector3<f64>) -> Self {
        Self {
            v,
            frame: PhantomData,
        }
    }

    /// `[x, y, z]`, declared to be in frame `F`.
    pub const fn from_array(a: [f64; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }

    /// The components as a bare nalgebra vector (the frame is dropped).
    pub const fn as_nalgebra(&self) -> &Vector3<f64> {
        &self.v
    }

    /// The components as a bare nalgebra vector, by value.
    pub const fn to_nalgebra(self) -> Vector3<f64> {
        self.v
    }

    /// `[x, y, z]`.
    pub fn to_array(&self) -> [f64; 3] {
        [self.v.x, self.v.y, self.v.z]
    }

    /// First component (forward in FRD, north in NED).
    pub fn x(&self) -> f64 {
        self.v.x
    }

    /// Second component (starboard in FRD, east in NED).
    pub fn y(&self) -> f64 {
        self.v.y
    }

    /// Third component (down in both).
    pub fn z(&self) -> f64 {
        self.v.z
    }

    /// Dot product with a vector of the same frame.
    pub fn dot(&self, other: &Self) -> f64 {
        self.v.dot(&other.v)
    }

    /// Cross product with a vector of the same frame.
    pub fn cross(&self, other: &Self) -> Self {
        Self::from_nalgebra(self.v.cross(&other.v))
    }

    /// Euclidean norm.
    pub fn norm(&self) -> f64 {
        self.v.norm()
    }

    /// The components x, y, z.
    pub fn iter(&self) -> impl Iterator<Item = &f64> {
        self.v.iter()
    }

    /// Every component finite.
    pub fn is_finite(&self) -> bool {
        self.v.iter().all(|c| c.is_finite())
    }
}

impl<F> Clone for Vector<F> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<F> Copy for Vector<F> {}

impl<F> PartialEq for Vector<F> {
    fn eq(&self, other: &Self) -> bool {
        self.v == other.v
    }
}

impl<F> Default for Vector<F> {
    fn default() -> Self {
        Self::zeros()
    }
}

impl<F> fmt::Debug for Vector<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let frame = std::any::type_name::<F>()
            .rsplit("::")
            .next()
            .unwrap_or("?");
        write!(
            f,
            "Vector<{frame}>({:?}, {:?}, {:?})",
            self.v.x, self.v.y, self.v.z
        )
    }
}

impl<F> Add for Vector<F> {
    type Output = Self;
    fn add(self, rhs: Self) -> Self {
        Self::from_nalgebra(self.v + rhs.v)
    }
}

impl<F> AddAssign for Vector<F> {
    fn add_assign(&mut self, rhs: Self) {
        self.v += rhs.v;
    }
}

impl<F> Sub for Vector<F> {
    type Output = Self;
    fn sub(self, rhs: Self) -> Self {
        Self::from_nalgebra(self.v - rhs.v)
    }
}

impl<F> SubAssign for Vector<F> {
    fn sub_assign(&mut self, rhs: Self) {
        self.v -= rhs.v;
    }
}

impl<F> Neg for Vector<F> {
    type Output = Self;
    fn neg(self) -> Self {
        Self::from_nalgebra(-self.v)
    }
}

impl<F> Mul<f64> for Vector<F> {
    type Output = Self;
    fn mul(self, s: f64) -> Self {
        Self::from_nalgebra(self.v * s)
    }
}

impl<F> Mul<Vector<F>> for f64 {
    type Output = Vector<F>;
    fn mul(self, v: Vector<F>) -> Vector<F> {
        Vector::from_nalgebra(self * v.v)
    }
}

impl<F> Div<f64> for Vector<F> {
    type Output = Self;
    fn div(self, s: f64) -> Self {
        Self::from_nalgebra(self.v / s)
    }
}

/// Component `i` (0 = x, 1 = y, 2 = z); panics beyond 2, as an array does.
impl<F> Index<usize> for Vector<F> {
    type Output = f64;
    fn index(&self, i: usize) -> &f64 {
        &self.v[i]
    }
}
