//! Bad URDFs get errors that name the link or joint.

use model::{ModelError, PlanarModel};

fn link(name: &str) -> String {
    format!("<link name=\"{name}\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial></link>")
}

fn joint(name: &str, kind: &str, parent: &str, child: &str, axis: &str) -> String {
    format!(
        "<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/><axis xyz=\"{axis}\"/><limit lower=\"-1\" upper=\"1\" effort=\"10\" velocity=\"10\"/></joint>"
    )
}

fn robot(body: &str) -> String {
    format!("<?xml version=\"1.0\"?><robot name=\"t\">{body}</robot>")
}

fn load(body: &str) -> Result<PlanarModel, ModelError> {
    PlanarModel::from_urdf_str(&robot(body), "test.urdf")
}

#[test]
fn a_two_link_pendulum_loads() {
    let m = load(&(link("a") + &link("b") + &joint("j", "revolute", "a", "b", "0 1 0")))
        .expect("loads");
    assert_eq!(m.dof(), 4);
    assert_eq!(m.total_mass_kg(), 2.0);
}

#[test]
fn missing_inertial_names_the_link() {
    let body = link("a") + "<link name=\"bare\"/>" + &joint("j", "revolute", "a", "bare", "0 1 0");
    let e = load(&body).expect_err("must fail");
    assert!(
        matches!(&e, ModelError::MissingInertial { link, .. } if link == "bare"),
        "{e}"
    );
    assert!(e.to_string().contains("test.urdf") && e.to_string().contains("'bare'"));
}

#[test]
fn non_planar_axis_names_the_joint() {
    let e = load(&(link("a") + &link("b") + &joint("roll", "revolute", "a", "b", "1 0 0")))
        .expect_err("must fail");
    assert!(
        matches!(&e, ModelError::NonPlanar { joint, .. } if joint == "roll"),
        "{e}"
    );
    let e = load(&(link("a") + &link("b") + &joint("slide", "prismatic", "a", "b", "0 1 0")))
        .expect_err("must fail");
    assert!(
        matches!(&e, ModelError::NonPlanar { joint, .. } if joint == "slide"),
        "{e}"
    );
}

#[test]
fn unknown_parent_names_the_joint_and_link() {
    let e =
        load(&(link("a") + &joint("j", "revolute", "ghost", "a", "0 1 0"))).expect_err("must fail");
    assert!(
        matches!(&e, ModelError::UnknownLink { joint, link, role: "parent", .. } if joint == "j" && link == "ghost"),
        "{e}"
    );
}

#[test]
fn a_loop_is_reported() {
    let body = link("a")
        + &link("b")
        + &link("c")
        + &joint("ab", "revolute", "a", "b", "0 1 0")
        + &joint("bc", "revolute", "b", "c", "0 1 0")
        + &joint("cb", "revolute", "c", "b", "0 1 0");
    let e = load(&body).expect_err("must fail");
    assert!(matches!(e, ModelError::NotATree { .. }), "{e}");
    assert!(e.to_string().contains("'b'"), "{e}");
    // A pure cycle has no root at all.
    let cycle = link("a")
        + &link("b")
        + &joint("ab", "revolute", "a", "b", "0 1 0")
        + &joint("ba", "revolute", "b", "a", "0 1 0");
    let e = load(&cycle).expect_err("must fail");
    assert!(matches!(e, ModelError::NotATree { .. }), "{e}");
}

#[test]
fn unsupported_joint_types_and_bad_values_are_named() {
    let e = load(&(link("a") + &link("b") + &joint("ball", "floating", "a", "b", "0 1 0")))
        .expect_err("must fail");
    assert!(
        matches!(&e, ModelError::UnsupportedJoint { joint, .. } if joint == "ball"),
        "{e}"
    );
    let neg = "<link name=\"n\"><inertial><mass value=\"-1\"/><inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/></inertial></link>";
    let e = load(neg).expect_err("must fail");
    assert!(
        matches!(&e, ModelError::BadInertial { link, field: "mass", .. } if link == "n"),
        "{e}"
    );
    let e = PlanarModel::from_urdf_str("<robot name=\"x\"><link name=\"a\">", "cut.urdf")
        .expect_err("must fail");
    assert!(matches!(e, ModelError::UrdfSyntax { .. }), "{e}");
    let e = PlanarModel::from_urdf_file("no/such/file.urdf").expect_err("must fail");
    assert!(e.to_string().contains("no/such/file.urdf"), "{e}");
}

#[test]
fn fixed_links_merge_into_their_parent_with_the_parallel_axis_theorem() {
    let body = link("a")
        + &link("tip")
        + "<joint name=\"f\" type=\"fixed\"><parent link=\"a\"/><child link=\"tip\"/><origin xyz=\"0 0 -0.5\" rpy=\"0 0 0\"/></joint>";
    let m = load(&body).expect("loads");
    assert_eq!(m.bodies.len(), 1);
    let i = m.bodies[0].inertia;
    assert_eq!(i.mass_kg, 2.0);
    assert!((i.com_xz_m[1] + 0.25).abs() < 1e-15);
    // 2 × 0.1 own + 2 × 1 kg × 0.25² shift.
    assert!((i.inertia_yy_kgm2 - (0.2 + 0.125)).abs() < 1e-15);
    let tip = m.frame_index("tip").expect("frame");
    assert_eq!(m.frames[tip].offset_xz_m, [0.0, -0.5]);
}

/// Issue #27: what urdf-rs accepted or reported without a name: a root tag `<robott>`, a negative
/// `ixx`, a duplicate link, a two-number `xyz`, a NaN joint origin ("not planar" before).
#[test]
fn malformed_attributes_name_the_element_the_field_and_the_value() {
    let text = robot(&(link("a") + &link("b") + &joint("j", "revolute", "a", "b", "0 1 0")))
        .replace("<robot ", "<robott ")
        .replace("</robot>", "</robott>");
    let e = PlanarModel::from_urdf_str(&text, "test.urdf").expect_err("robott");
    assert!(
        matches!(e, ModelError::UrdfSyntax { .. }) && e.to_string().contains("<robott>"),
        "{e}"
    );

    let negative = link("a").replacen("ixx=\"0.1\"", "ixx=\"-0.1\"", 1)
        + &link("b")
        + &joint("j", "revolute", "a", "b", "0 1 0");
    let e = load(&negative).expect_err("negative ixx").to_string();
    assert!(
        e.contains("link 'a'") && e.contains("inertia ixx") && e.contains("-0.1"),
        "{e}"
    );

    let twice = link("a") + &link("b") + &link("b") + &joint("j", "revolute", "a", "b", "0 1 0");
    let e = load(&twice).expect_err("duplicate").to_string();
    assert!(
        e.contains("link 'b'") && e.contains("defined already"),
        "{e}"
    );

    let with_origin = |xyz: &str| {
        link("a")
            + &link("b")
            + &joint("knee", "revolute", "a", "b", "0 1 0").replace(
                "<axis",
                &format!("<origin xyz=\"{xyz}\" rpy=\"0 0 0\"/><axis"),
            )
    };
    let e = load(&with_origin("0 -0.5"))
        .expect_err("two numbers")
        .to_string();
    assert!(
        e.contains("joint 'knee'") && e.contains("origin xyz") && e.contains("found 2"),
        "{e}"
    );
    let e = load(&with_origin("NaN 0 -0.5")).expect_err("NaN origin");
    assert!(
        matches!(&e, ModelError::UrdfField { field, .. } if field == "origin xyz"),
        "{e}"
    );
    assert!(
        e.to_string().contains("joint 'knee'") && e.to_string().contains("NaN"),
        "{e}"
    );
}
