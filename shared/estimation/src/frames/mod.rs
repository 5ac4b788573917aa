//! Frames in types (STYLE item 3, in the spirit of `sguaba`): a vector or a
//! rotation says its frame in its type, so a body-frame vector where a
//! navigation-frame one is expected, or the sum of vectors of two frames, does
//! not compile. The types are zero-cost wrappers over nalgebra (a
//! [`Vector3`](nalgebra::Vector3) or a [`UnitQuaternion`](nalgebra::UnitQuaternion)
//! and a zero-sized marker); every operation does nalgebra's arithmetic in
//! nalgebra's order, so results are bit for bit those of the bare types.
//!
//! - [`Frd`]: the body frame, x forward, y starboard, z down.
//! - [`Ned`]: the navigation frame, x north, y east, z down.
//! - [`Vector<F>`]: a 3-vector in frame `F`.
//! - [`Rotation<From, To>`]: the rotation taking `From` vectors into `To`
//!   (`Rotation<Frd, Ned>` is the attitude `q_nb`), and the one conversion
//!   between the wire's `[w, x, y, z]` and the math quaternion
//!   ([`Rotation::from_wxyz`], [`Rotation::to_wxyz`]).
//!
//! Moving between a typed value and bare nalgebra is always by name
//! ([`Vector::from_nalgebra`], [`Vector::as_nalgebra`], ...), never implicit.
//!
//! A body-frame vector is not a navigation-frame one:
//!
//! ```compile_fail
//! use nauta_estimation::frames::{Frd, Ned, Vector};
//! fn north_of(v: &Vector<Ned>) -> f64 { v.x() }
//! let body = Vector::<Frd>::new(1.0, 0.0, 0.0);
//! north_of(&body);
//! ```
//!
//! whereas the same call with a NED vector compiles:
//!
//! ```
//! use nauta_estimation::frames::{Ned, Vector};
//! fn north_of(v: &Vector<Ned>) -> f64 { v.x() }
//! let nav = Vector::<Ned>::new(1.0, 0.0, 0.0);
//! assert_eq!(north_of(&nav), 1.0);
//! ```
//!
//! A body-frame vector cannot be added to a NED one:
//!
//! ```compile_fail
//! use nauta_estimation::frames::{Frd, Ned, Vector};
//! let v_body = Vector::<Frd>::new(1.0, 0.0, 0.0);
//! let v_nav = Vector::<Ned>::new(0.0, 1.0, 0.0);
//! let _ = v_nav + v_body;
//! ```
//!
//! but rotated into NED first, it can:
//!
//! ```
//! use nauta_estimation::frames::{Frd, Ned, Rotation, Vector};
//! let v_body = Vector::<Frd>::new(1.0, 0.0, 0.0);
//! let v_nav = Vector::<Ned>::new(0.0, 1.0, 0.0);
//! let q_nb = Rotation::<Frd, Ned>::identity();
//! let sum = v_nav + q_nb * v_body;
//! assert_eq!(sum, Vector::<Ned>::new(1.0, 1.0, 0.0));
//! ```
//!
//! A rotation applies only to vectors of its source frame, and composes only
//! head to tail:
//!
//! ```compile_fail
//! use nauta_estimation::frames::{Frd, Ned, Rotation, Vector};
//! let q_nb = Rotation::<Frd, Ned>::identity();
//! let _ = q_nb * Vector::<Ned>::new(1.0, 0.0, 0.0);
//! ```
//!
//! ```compile_fail
//! use nauta_estimation::frames::{Frd, Ned, Rotation};
//! let q_nb = Rotation::<Frd, Ned>::identity();
//! let _: Rotation<Frd, Ned> = q_nb * q_nb;
//! ```
//!
//! ```
//! use nauta_estimation::frames::{Frd, Ned, Rotation, Vector};
//! let q_nb = Rotation::<Frd, Ned>::identity();
//! let _: Vector<Ned> = q_nb * Vector::<Frd>::new(1.0, 0.0, 0.0);
//! let _: Rotation<Frd, Frd> = q_nb.inverse() * q_nb;
//! ```

mod rotation;
mod vector;

pub use rotation::{Rotation, WxyzError};
pub use vector::Vector;

/// The body frame: x forward, y starboard, z down.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Frd;

/// The navigation frame: x north, y east, z down.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Ned;

#[cfg(test)]
mod tests;
