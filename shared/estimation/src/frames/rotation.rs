//! [`Rotation<From, To>`]: a rotation between two frames, and the one
//! conversion between the wire's `[w, x, y, z]` and the math quaternion.

use std::fmt;
use std::marker::PhantomData;
use std::ops::Mul;

use nalgebra::{Quaternion, UnitQuaternion};
use thiserror::Error;

use super::{Frd, Ned, Vector};

/// Why [`Rotation::from_wxyz`] refused four numbers.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum WxyzError {
    /// A component is NaN or infinite.
    #[error("quaternion holds a non-finite number")]
    NonFinite,
    /// The norm is not within the tolerance of 1.
    #[error("quaternion has norm {0}, not 1")]
    NotUnit(f64),
}

/// The rotation taking vectors of frame `From` into frame `To`, a unit
/// quaternion (Hamilton). `Rotation<Frd, Ned>` is the attitude `q_nb`.
pub struct Rotation<From, To> {
    q: UnitQuaternion<f64>,
    frames: PhantomData<(From, To)>,
}

impl<From, To> Rotation<From, To> {
    /// How far from 1 the norm of a quaternion given to [`Self::from_wxyz`] may
    /// be (the wire's tolerance: an `f32`-rounded or re-serialised quaternion
    /// passes, anything else is not a rotation).
    pub const NORM_TOLERANCE: f64 = 1e-3;

    /// The identity.
    pub fn identity() -> Self {
        Self::from_nalgebra(UnitQuaternion::identity())
    }

    /// The nalgebra unit quaternion `q`, declared to rotate `From` into `To`.
    pub const fn from_nalgebra(q: UnitQuaternion<f64>) -> Self {
        Self {
            q,
            frames: PhantomData,
        }
    }

    /// The bare nalgebra unit quaternion (the frames are dropped).
    pub const fn as_nalgebra(&self) -> &UnitQuaternion<f64> {
        &self.q
    }

    /// The bare nalgebra unit quaternion, by value.
    pub const fn to_nalgebra(self) -> UnitQuaternion<f64> {
        self.q
    }

    /// The quaternion of the wire's `[w, x, y, z]` order, unchecked and not
    /// normalised: the one place that maps that order onto nalgebra's.
    pub fn quaternion_from_wxyz(q: [f64; 4]) -> Quaternion<f64> {
        Quaternion::new(q[0], q[1], q[2], q[3])
    }

    /// The rotation of `[w, x, y, z]`, checked: every component finite and the
    /// norm within [`Self::NORM_TOLERANCE`] of 1; renormalised.
    pub fn from_wxyz(q: [f64; 4]) -> Result<Self, WxyzError> {
        Self::from_wxyz_within(q, Self::NORM_TOLERANCE)
    }

    /// As [`Self::from_wxyz`] with the norm tolerance `tolerance`.
    pub fn from_wxyz_within(q: [f64; 4], tolerance: f64) -> Result<Self, WxyzError> {
        if !q.iter().all(|c| c.is_finite()) {
            return Err(WxyzError::NonFinite);
        }
        let quat = Self::quaternion_from_wxyz(q);
        let norm = quat.norm();
        if !((norm - 1.0).abs() <= tolerance) {
            return Err(WxyzError::NotUnit(norm));
        }
        Ok(Self::from_nalgebra(UnitQuaternion::new_normalize(quat)))
    }

    /// The rotation of `[w, x, y, z]` with its bits kept (not renormalised)
    /// when its norm is 1 to rounding (within 4 ε), so that a published state
    /// is continued exactly; `None` otherwise.
    pub fn from_wxyz_exact(q: [f64; 4]) -> Option<Self> {
        let quat = Self::quaternion_from_wxyz(q);
        ((quat.norm() - 1.0).abs() <= 4.0 * f64::EPSILON)
            .then(|| Self::from_nalgebra(UnitQuaternion::new_unchecked(quat)))
    }

    /// `[w, x, y, z]`, the wire's order.
    pub fn to_wxyz(&self) -> [f64; 4] {
        [self.q.w, self.q.i, self.q.j, self.q.k]
    }

    /// The inverse rotation, `To` into `From`.
    pub fn inverse(&self) -> Rotation<To, From> {
        Rotation::from_nalgebra(self.q.inverse())
    }

    /// The angle of the rotation taking `self` onto `other`, rad, in [0, π].
    pub fn angle_to(&self, other: &Self) -> f64 {
        self.q.angle_to(&other.q)
    }
}

impl Rotation<Frd, Ned> {
    /// The attitude of roll, pitch and yaw (rad), aerospace ZYX sequence
    /// ([`crate::attitude::from_euler`]).
    pub fn from_euler(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> Self {
        Self::from_nalgebra(crate::attitude::from_euler(roll_rad, pitch_rad, yaw_rad))
    }

    /// Roll, pitch and yaw (rad) of the attitude ([`crate::attitude::to_euler`]).
    pub fn euler(&self) -> (f64, f64, f64) {
        crate::attitude::to_euler(&self.q)
    }
}

impl<From, To> Clone for Rotation<From, To> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<From, To> Copy for Rotation<From, To> {}

impl<From, To> PartialEq for Rotation<From, To> {
    fn eq(&self, other: &Self) -> bool {
        self.q == other.q
    }
}

impl<From, To> fmt::Debug for Rotation<From, To> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = |t: &'static str| t.rsplit("::").next().unwrap_or("?");
        write!(
            f,
            "Rotation<{}, {}>({:?})",
            name(std::any::type_name::<From>()),
            name(std::any::type_name::<To>()),
            self.to_wxyz()
        )
    }
}

/// `q_ab * v_b = v_a`.
impl<From, To> Mul<Vector<From>> for Rotation<From, To> {
    type Output = Vector<To>;
    fn mul(self, v: Vector<From>) -> Vector<To> {
        Vector::from_nalgebra(self.q * v.to_nalgebra())
    }
}

/// Composition head to tail: `(B → C) * (A → B) = A → C`.
impl<A, B, C> Mul<Rotation<A, B>> for Rotation<B, C> {
    type Output = Rotation<A, C>;
    fn mul(self, rhs: Rotation<A, B>) -> Rotation<A, C> {
        Rotation::from_nalgebra(self.q * rhs.q)
    }
}
