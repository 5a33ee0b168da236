//! The robot co-designed for 0.20, 0.25 and 0.30 m/s together, shipped as
//! `configs/robots/adam_codesign_speeds.urdf`, is what its command produces:
//! `adam codesign --speeds 0.20,0.25,0.30 --config configs/planner/adam_electrical.toml
//! --out-urdf configs/robots/adam_codesign_speeds.urdf --out-gait out/gaits/adam_codesign_speeds.json --force`.

use model::design::{generate_urdf_with, DesignLengths};
use planner::config::PlannerConfig;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// The lengths a generated URDF states in its header comment ("for thigh X m and shin Y m").
fn stated_lengths(urdf: &str) -> [f64; 2] {
    let number_after = |key: &str| -> f64 {
        let rest = &urdf[urdf.find(key).expect(key) + key.len()..];
        rest.split_whitespace()
            .next()
            .and_then(|w| w.parse().ok())
            .expect("a length")
    };
    [number_after("for thigh "), number_after("and shin ")]
}

/// The composite co-design (one NLP, shared lengths, the A1 electrical cost) ends at the shipped
/// lengths, and the shipped file is GenerateModel's URDF there with the A1 drives, byte for byte.
#[test]
fn the_shipped_three_speed_robot_is_what_the_command_produces() {
    let config = PlannerConfig::load(format!("{ROOT}/configs/planner/adam_electrical.toml"))
        .expect("electrical config");
    let path = format!("{ROOT}/configs/robots/adam_codesign_speeds.urdf");
    let shipped = std::fs::read_to_string(&path).expect("shipped URDF");
    let [thigh, shin] = stated_lengths(&shipped);
    let regenerated = generate_urdf_with(
        &DesignLengths {
            thigh_length_m: thigh,
            shin_length_m: shin,
        },
        &config.codesign.mass_model(),
    )
    .expect("generates");
    assert_eq!(
        shipped, regenerated,
        "{path} is GenerateModel's URDF at its lengths with the config's mass model"
    );
    let r = planner::codesign::codesign_speeds(&config, &[0.20, 0.25, 0.30], "robot.urdf")
        .expect("co-designs");
    println!(
        "shared design {:?} m, mean objective {:.5}, {} iterations",
        r.lengths_m, r.mean_cost, r.iterations
    );
    for (found, stated) in r.lengths_m.iter().zip([thigh, shin]) {
        assert!(
            (found - stated).abs() < 1e-6,
            "the command finds {:?} m, {path} states [{thigh}, {shin}] m",
            r.lengths_m
        );
    }
    // The thigh is interior (the shin at Table I's upper bound, 0.35 m).
    assert!((0.16..0.349).contains(&r.lengths_m[0]), "{:?}", r.lengths_m);
    // Every speed's gait on the shared robot walks its plan (issue #28 item 5).
    let model = model::PlanarModel::from_urdf_str(&r.urdf, "shared").expect("robot");
    for g in &r.gaits {
        planner::verify::assert_orbit_matches_plan(&model, &g.gait);
    }
}
