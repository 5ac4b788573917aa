//! The frame types against bare nalgebra: the same bits for every operation,
//! the wire round trip, and the checks of `from_wxyz`.

use super::*;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use proptest::prelude::*;

fn bits3(v: &Vector3<f64>) -> [u64; 3] {
    [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()]
}

fn bits4(q: &[f64; 4]) -> [u64; 4] {
    q.map(f64::to_bits)
}

fn unit() -> impl Strategy<Value = [f64; 4]> {
    prop::array::uniform4(-1.0f64..1.0).prop_filter("not near zero", |q| {
        q.iter().map(|c| c * c).sum::<f64>() > 1e-3
    })
}

fn vec3() -> impl Strategy<Value = [f64; 3]> {
    prop::array::uniform3(-100.0f64..100.0)
}

fn nalgebra_unit(q: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_normalize(Quaternion::new(q[0], q[1], q[2], q[3]))
}

#[test]
fn from_wxyz_checks_and_names_the_order() {
    let h = 0.5f64.sqrt();
    // 90° yaw: w and z carry it, and the body x axis goes east.
    let q = Rotation::<Frd, Ned>::from_wxyz([h, 0.0, 0.0, h]).expect("unit");
    assert_eq!(q.as_nalgebra().w, q.to_wxyz()[0]);
    assert_eq!(q.as_nalgebra().k, q.to_wxyz()[3]);
    let east = q * Vector::<Frd>::new(1.0, 0.0, 0.0);
    assert!((east - Vector::<Ned>::new(0.0, 1.0, 0.0)).norm() < 1e-15);
    assert_eq!(
        Rotation::<Frd, Ned>::from_wxyz([f64::NAN, 0.0, 0.0, 0.0]),
        Err(WxyzError::NonFinite)
    );
    assert_eq!(
        Rotation::<Frd, Ned>::from_wxyz([1.0, f64::INFINITY, 0.0, 0.0]),
        Err(WxyzError::NonFinite)
    );
    assert!(matches!(
        Rotation::<Frd, Ned>::from_wxyz([1.0, 1.0, 0.0, 0.0]),
        Err(WxyzError::NotUnit(n)) if (n - 2f64.sqrt()).abs() < 1e-15
    ));
    assert!(matches!(
        Rotation::<Frd, Ned>::from_wxyz([0.0; 4]),
        Err(WxyzError::NotUnit(_))
    ));
    // Within the tolerance, renormalised.
    let q = Rotation::<Frd, Ned>::from_wxyz([1.0005, 0.0, 0.0, 0.0]).expect("within");
    assert_eq!(q.to_wxyz(), [1.0, 0.0, 0.0, 0.0]);
    assert!(Rotation::<Frd, Ned>::from_wxyz_within([1.0005, 0.0, 0.0, 0.0], 1e-6).is_err());
    // Exact: the bits kept at norm 1 to rounding, refused beyond.
    let raw = [1.0 + 2.0 * f64::EPSILON, 0.0, 0.0, 0.0];
    let exact = Rotation::<Frd, Ned>::from_wxyz_exact(raw).expect("unit to rounding");
    assert_eq!(bits4(&exact.to_wxyz()), bits4(&raw));
    assert!(Rotation::<Frd, Ned>::from_wxyz_exact([1.0 + 1e-12, 0.0, 0.0, 0.0]).is_none());
}

#[test]
fn vector_arithmetic_is_nalgebras() {
    let a = Vector3::new(1.5, -2.25, 3.0);
    let b = Vector3::new(0.1, 0.2, -0.3);
    let (ta, tb) = (
        Vector::<Ned>::from_nalgebra(a),
        Vector::<Ned>::from_nalgebra(b),
    );
    assert_eq!(bits3((ta + tb).as_nalgebra()), bits3(&(a + b)));
    assert_eq!(bits3((ta - tb).as_nalgebra()), bits3(&(a - b)));
    assert_eq!(bits3((-ta).as_nalgebra()), bits3(&(-a)));
    assert_eq!(bits3((ta * 0.3).as_nalgebra()), bits3(&(a * 0.3)));
    assert_eq!(bits3((0.3 * ta).as_nalgebra()), bits3(&(0.3 * a)));
    assert_eq!(bits3((ta / 0.7).as_nalgebra()), bits3(&(a / 0.7)));
    assert_eq!(bits3(ta.cross(&tb).as_nalgebra()), bits3(&a.cross(&b)));
    assert_eq!(ta.dot(&tb).to_bits(), a.dot(&b).to_bits());
    assert_eq!(ta.norm().to_bits(), a.norm().to_bits());
    let mut c = ta;
    c += tb;
    c -= ta;
    assert_eq!(bits3(c.as_nalgebra()), bits3(&(a + b - a)));
    assert_eq!(ta.to_array(), [1.5, -2.25, 3.0]);
    assert_eq!(Vector::<Frd>::from_array([1.0, 2.0, 3.0]).z(), 3.0);
    assert!(!Vector::<Frd>::new(f64::NAN, 0.0, 0.0).is_finite());
    assert_eq!(
        format!("{:?}", Vector::<Frd>::new(1.0, 2.0, 3.0)),
        "Vector<Frd>(1.0, 2.0, 3.0)"
    );
}

#[test]
fn euler_is_the_attitude_modules() {
    let (r, p, y) = (0.3, -0.2, 2.5);
    let q = Rotation::<Frd, Ned>::from_euler(r, p, y);
    let bare = crate::attitude::from_euler(r, p, y);
    assert_eq!(
        bits4(&q.to_wxyz()),
        bits4(&[bare.w, bare.i, bare.j, bare.k])
    );
    let (er, ep, ey) = q.euler();
    let want = crate::attitude::to_euler(&bare);
    assert_eq!(
        [er, ep, ey].map(f64::to_bits),
        [want.0, want.1, want.2].map(f64::to_bits)
    );
}

proptest! {
    #[test]
    fn wxyz_round_trip(q in unit()) {
        let n = nalgebra_unit(&q);
        let w = [n.w, n.i, n.j, n.k];
        let r = Rotation::<Frd, Ned>::from_wxyz(w).expect("unit");
        // In and out: nalgebra's renormalisation bit for bit, and the same
        // rotation to rounding; the order is w first.
        let m = nalgebra_unit(&w);
        prop_assert_eq!(bits4(&r.to_wxyz()), bits4(&[m.w, m.i, m.j, m.k]));
        prop_assert!(r.to_wxyz().iter().zip(&w).all(|(a, b)| (a - b).abs() <= 4.0 * f64::EPSILON));
        // Exactly unit quaternions pass `from_wxyz_exact` with their bits.
        if let Some(e) = Rotation::<Frd, Ned>::from_wxyz_exact(w) {
            prop_assert_eq!(bits4(&e.to_wxyz()), bits4(&w));
        }
        // A non-unit array within the tolerance is nalgebra's renormalisation.
        let scaled = q.map(|c| c * (1.0 + 5e-4) / q.iter().map(|c| c * c).sum::<f64>().sqrt());
        let r = Rotation::<Ned, Frd>::from_wxyz(scaled).expect("within tolerance");
        prop_assert_eq!(bits4(&r.to_wxyz()), {
            let m = nalgebra_unit(&scaled);
            bits4(&[m.w, m.i, m.j, m.k])
        });
    }

    #[test]
    fn rotation_inverse_and_composition_are_nalgebras(
        a in unit(), b in unit(), v in vec3()
    ) {
        let (qa, qb) = (nalgebra_unit(&a), nalgebra_unit(&b));
        let v3 = Vector3::from(v);
        let r_nb = Rotation::<Frd, Ned>::from_nalgebra(qa);
        let r_bb = Rotation::<Frd, Frd>::from_nalgebra(qb);
        let v_b = Vector::<Frd>::from_nalgebra(v3);
        prop_assert_eq!(bits3((r_nb * v_b).as_nalgebra()), bits3(&(qa * v3)));
        let r_bn = r_nb.inverse();
        prop_assert_eq!(r_bn.to_nalgebra(), qa.inverse());
        let back = r_bn * (r_nb * v_b);
        prop_assert!((back - v_b).norm() <= 1e-12 * (1.0 + v_b.norm()));
        let composed: Rotation<Frd, Ned> = r_nb * r_bb;
        prop_assert_eq!(composed.to_nalgebra(), qa * qb);
        prop_assert_eq!(bits3((composed * v_b).as_nalgebra()), bits3(&((qa * qb) * v3)));
        prop_assert!((composed * v_b - r_nb * (r_bb * v_b)).norm() <= 1e-12 * (1.0 + v_b.norm()));
        let identity: Rotation<Frd, Frd> = r_bn * r_nb;
        prop_assert!(identity.angle_to(&Rotation::identity()) < 1e-7);
    }
}
