//! GenerateModel: inertia fits, the generated URDF, and the committed ADAM URDF.

mod common;

use model::design::*;
use model::{PlanarModel, Side};

#[test]
fn cubic_fits_follow_the_parametric_geometry_within_one_percent() {
    let fits = InertiaFits::adam();
    assert!(fits.sample_lengths_m.len() >= 6);
    let thigh = fits.thigh.max_relative_error(thigh_properties, 201);
    let shin = fits.shin.max_relative_error(shin_properties, 201);
    println!("inertia fit max relative error over 201 lengths: thigh {thigh:.2e}, shin {shin:.2e}");
    assert!(thigh < 0.01 && shin < 0.01, "thigh {thigh}, shin {shin}");
}

#[test]
fn geometry_is_physical_and_monotone_in_length() {
    let mut last = thigh_properties(DESIGN_MIN_M);
    for i in 1..=20 {
        let l = DESIGN_MIN_M + (DESIGN_MAX_M - DESIGN_MIN_M) * i as f64 / 20.0;
        let p = thigh_properties(l);
        assert!(
            p.mass_kg > last.mass_kg
                && p.iyy_kgm2 > last.iyy_kgm2
                && p.com_distance_m > last.com_distance_m
        );
        assert!(p.com_distance_m > 0.0 && p.com_distance_m < l);
        // Triangle inequality of principal moments.
        assert!(p.ixx_kgm2 + p.iyy_kgm2 >= p.izz_kgm2 && p.iyy_kgm2 + p.izz_kgm2 >= p.ixx_kgm2);
        last = p;
    }
}

#[test]
fn generated_urdf_reparses_into_a_model_with_the_fitted_inertias_and_lengths() {
    let fits = InertiaFits::adam();
    for (t, s) in [(0.15, 0.35), (0.24, 0.25), (0.35, 0.15), (0.2, 0.3)] {
        let design = DesignLengths {
            thigh_length_m: t,
            shin_length_m: s,
        };
        let (model, text) = generate_model(&design).expect("generates");
        let again = PlanarModel::from_urdf_str(&text, "again").expect("reparses");
        assert_eq!(model, again);
        let q = model.nominal_pose().expect("pose");
        for side in [Side::Left, Side::Right] {
            let (lt, ls) = model.leg_lengths(&q, side).expect("lengths");
            assert!(
                (lt - t).abs() < 1e-12 && (ls - s).abs() < 1e-12,
                "{lt} {ls}"
            );
        }
        let thigh =
            &model.bodies[model.joints[model.require_joint("left_hip_pitch").expect("hip")].body];
        let fit = fits.thigh.at(t);
        assert!((thigh.inertia.mass_kg - fit.mass_kg).abs() < 1e-12);
        assert!((thigh.inertia.com_xz_m[1] + fit.com_distance_m).abs() < 1e-12);
        assert!((thigh.inertia.inertia_yy_kgm2 - fit.iyy_kgm2).abs() < 1e-12);
        // Design joints move each length over exactly the design range.
        let legs = model.legs().expect("legs");
        let td = &model.joints[legs.left.thigh_design.expect("design joint")];
        assert!(
            (td.lower + t - DESIGN_MIN_M).abs() < 1e-12
                && (td.upper + t - DESIGN_MAX_M).abs() < 1e-12
        );
        let q2 = model.with_design(&q, 0.3, 0.2).expect("design");
        let (lt, ls) = model.leg_lengths(&q2, Side::Right).expect("lengths");
        assert!((lt - 0.3).abs() < 1e-12 && (ls - 0.2).abs() < 1e-12);
    }
}

#[test]
fn designs_outside_the_range_are_refused_with_the_value() {
    let e = generate_urdf(&DesignLengths {
        thigh_length_m: 0.5,
        shin_length_m: 0.25,
    })
    .expect_err("out of range");
    assert!(e.to_string().contains("thigh_length_m = 0.5"), "{e}");
}

/// The committed URDF is GenerateModel's output for the hardware ADAM.
/// Re-mint with: `cargo run --release -- generate-urdf --thigh 0.24 --shin 0.25 --out configs/robots/adam_planar.urdf`
#[test]
fn committed_adam_urdf_is_the_generated_one() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/robots/adam_planar.urdf"
    );
    let committed = std::fs::read_to_string(path).expect("configs/robots/adam_planar.urdf");
    assert_eq!(
        committed,
        generate_urdf(&DesignLengths::ADAM).expect("generates")
    );
    let model = PlanarModel::from_urdf_file(path).expect("loads");
    let mass = model.total_mass_kg();
    assert!((15.0..18.0).contains(&mass), "total mass {mass} kg");
}

/// The link-density scale moves only the tubes' mass, the fits follow it, and scale 1 is the
/// shipped model.
#[test]
#[allow(clippy::unwrap_used)]
fn link_density_scale_scales_the_tubes_and_the_fits_follow() {
    use model::design::{
        generate_model_with, generate_urdf_with, shin_properties_with, thigh_properties_with,
        InertiaFits, MassModel,
    };
    let one = MassModel::default();
    let heavy = MassModel {
        link_density_scale: 1.5,
        ..MassModel::default()
    };
    for l in [0.15, 0.24, 0.35] {
        // Tube mass by hand: ρ π (r_o² − r_i²) × its length (thigh: L − 0.10 m, shin: L − 0.07 m).
        let per_m = 2700.0 * std::f64::consts::PI * (0.020f64.powi(2) - 0.018f64.powi(2));
        let dt = thigh_properties_with(l, &heavy).mass_kg - thigh_properties_with(l, &one).mass_kg;
        let ds = shin_properties_with(l, &heavy).mass_kg - shin_properties_with(l, &one).mass_kg;
        assert!((dt - 0.5 * per_m * (l - 0.10)).abs() < 1e-12, "{dt}");
        assert!((ds - 0.5 * per_m * (l - 0.07)).abs() < 1e-12, "{ds}");
    }
    let fits = InertiaFits::adam_with(&heavy);
    assert!(
        fits.thigh
            .max_relative_error(|l| thigh_properties_with(l, &heavy), 201)
            < 0.01
    );
    assert!(
        fits.shin
            .max_relative_error(|l| shin_properties_with(l, &heavy), 201)
            < 0.01
    );
    assert_eq!(
        generate_urdf_with(&DesignLengths::ADAM, &one).unwrap(),
        generate_urdf(&DesignLengths::ADAM).unwrap()
    );
    let (m1, _) = generate_model_with(&DesignLengths::ADAM, &one).unwrap();
    let (m15, text) = generate_model_with(&DesignLengths::ADAM, &heavy).unwrap();
    assert!(text.contains("density scaled by 1.5"));
    assert!(m15.total_mass_kg() > m1.total_mass_kg() + 0.1);
    for bad in [0.0, -1.0, f64::NAN] {
        let e = generate_urdf_with(
            &DesignLengths::ADAM,
            &MassModel {
                link_density_scale: bad,
                ..MassModel::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("link_density_scale"), "{e}");
    }
}
