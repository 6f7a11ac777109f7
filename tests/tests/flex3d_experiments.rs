//! Every FLEX3D experiment of Nedel 1993 as a test of the criterion the specification gives (spec S6).
//! The measuring code is the same that `cargo xtask reproduce` prints.

use anima_cloth::flex3d::FrictionMode;
use anima_lab::flex3d::{self, ThesisScene};
use anima_ode::Integrator;

#[test]
fn e1_table_4_1_all_66_values_equal_the_printed_digits() {
    let t = flex3d::e1_table_4_1(Integrator::ForwardEuler);
    for (i, (thesis, ours)) in t.thesis.iter().zip(&t.ours).enumerate() {
        for (c, (a, b)) in thesis.iter().zip(ours).enumerate() {
            assert_eq!(a, b, "t = {i}, h = {}: thesis {a}, anima {b}", t.steps[c]);
        }
    }
    assert_eq!(t.matches, 66);
}

#[test]
fn e1_error_shrinks_tenfold_with_each_tenfold_cut_in_h() {
    use anima_cloth::flex3d::mass_spring::{SingleSpring, trajectory};
    let exact = SingleSpring::thesis().exact(10.0);
    let err = |h: f64| (trajectory(Integrator::ForwardEuler, h, 10)[10] - exact).abs();
    for h in [0.005, 0.0005] {
        let ratio = err(h) / err(h / 10.0);
        assert!(
            (8.0..12.5).contains(&ratio),
            "h = {h}: error ratio {ratio}, expected about 10 (first order)"
        );
    }
    // h = 1.0 blows up exactly as printed: 4, 4, 2, −2, −6, −6, 2, 18, 34, 34, 2.
    assert_eq!(
        trajectory(Integrator::ForwardEuler, 1.0, 10),
        [4.0, 4.0, 2.0, -2.0, -6.0, -6.0, 2.0, 18.0, 34.0, 34.0, 2.0]
    );
}

#[test]
fn e2_small_steps_agree_and_large_steps_diverge() {
    let s = flex3d::e2_step_sweep(FrictionMode::Literal).unwrap();
    let d = &s.max_deviation;
    assert!(d[2] < 1.0 && d[3] < 1.0, "h = 0.01 and 0.005 must agree with h = 0.001 within 1: {d:?}");
    assert!(d[0] > 5.0 && d[1] > 5.0, "h = 0.1 and 0.05 must be visibly wrong (> 5): {d:?}");
    assert!(d[0] > 18.0, "h = 0.1 must be off by more than the sheet's width: {d:?}");
    assert!(d[0] > d[1] && d[1] > d[2] && d[2] > d[3], "error must fall with h: {d:?}");
}

#[test]
fn e3_curtain_is_at_rest_by_frame_25() {
    for friction in [FrictionMode::Literal, FrictionMode::Viscous] {
        let c = flex3d::e3_curtain(friction).unwrap();
        assert!(c.max_speed[24] < 0.01, "{friction:?}: max speed at frame 25 = {}", c.max_speed[24]);
        assert!(c.max_speed[1] > 1.0, "{friction:?}: the curtain must move early on: {}", c.max_speed[1]);
    }
    // The spec's reconstruction (literal friction): the bottom row settles at y = 12.535.
    let c = flex3d::e3_curtain(FrictionMode::Literal).unwrap();
    assert!((c.bottom_row_y[24] - 12.535).abs() < 0.01, "bottom row at {}", c.bottom_row_y[24]);
    assert!((c.bottom_row_y[0] - 19.97).abs() < 0.01, "bottom row at t = 1 s: {}", c.bottom_row_y[0]);
}

#[test]
fn e4_paper_leaves_its_plane_and_drifts_down() {
    let s = flex3d::peeling_sheet(ThesisScene::Paper, FrictionMode::Literal, true).unwrap();
    for k in 3..=19 {
        assert!(s.min_free_z[k - 1] > 0.0, "frame {k}: a free particle has z = {}", s.min_free_z[k - 1]);
    }
    let fall = s.mean_free_y[2] - s.mean_free_y[18];
    assert!(fall >= 10.0, "mean y of the free particles fell only {fall} from frame 3 to 19");
    // The spec's free-corner trace: z ≈ 11 and y ≈ 29 at frame 9.
    let c = s.corner[8];
    assert!((c.z - 11.0).abs() < 1.0 && (c.y - 29.0).abs() < 1.5, "corner at frame 9: {c}");
}

#[test]
fn e5_wind_billows_the_sail_downwind() {
    let w = flex3d::e5_wind(true).unwrap();
    assert!(w.min_z.iter().all(|&z| z >= 0.0), "the sheet moved upwind: {:?}", w.min_z);
    assert!((w.z_extent[11] - 46.0).abs() < 1.0, "z extent at frame 12: {}", w.z_extent[11]);
    assert!(w.max_speed_last > 0.1, "still moving at t = 4 s");
    // The spec computed its numbers without collision handling; that run reproduces them exactly.
    let free = flex3d::e5_wind(false).unwrap();
    assert!(
        free.free_corner_furthest.iter().skip(2).all(|&b| b),
        "corner (9, 9) must lead: {:?}",
        free.free_corner_furthest
    );
    assert!((free.z_extent[19] - 58.0).abs() < 1.0, "z extent at frame 20: {}", free.z_extent[19]);
}

/// The search of the report's E-5 section: the faithful response tears the sail; reading A-3 as "all
/// three vertices" keeps it in shape and changes nothing before the sheet first meets itself.
#[test]
fn e5_three_vertex_contact_keeps_the_sail_in_shape() {
    let rows = flex3d::e5_search().unwrap();
    let row = |start: &str| rows.iter().find(|r| r.reading.name.starts_with(start)).expect(start);
    let free_peak = row("no self-collision").peak_speed;
    let faithful = row("faithful");
    assert!(!faithful.keeps_shape(free_peak), "the faithful response no longer tears the sail: {faithful:?}");
    assert!(faithful.peak_speed > 2.0 * free_peak, "{faithful:?} against {free_peak}");
    assert!(faithful.leads_through < 19, "{faithful:?}");
    for name in ["contact partner: all three vertices", "all three vertices, Δt halved"] {
        let three = row(name);
        assert!(three.keeps_shape(free_peak), "{three:?} (peak without collisions {free_peak})");
        assert_eq!(three.leads_through, 20, "{three:?}");
    }
    let three = row("contact partner: all three vertices");
    assert_eq!(
        three.extent_12, faithful.extent_12,
        "the reading must change nothing before the first contact"
    );
    assert!(three.responses > 0, "the three-vertex run must still meet itself: {three:?}");
    // The faithful response tears at half the step too: the step is not the cause.
    assert!(!row("Δt halved").keeps_shape(free_peak));
}

#[test]
fn e6_theatre_curtains_close_and_reopen_without_touching() {
    let t = flex3d::e6_theatre().unwrap();
    assert_eq!(t.frames, 145);
    assert!(t.matches_e3_first_25, "corte must repeat E-3 bit for bit while the rails are still");
    for c in 0..2 {
        assert!(
            (t.closed_displacement[c] - 22.79).abs() < 1e-9,
            "rail {c} moved {}",
            t.closed_displacement[c]
        );
        // 0.57 × 40 − 0.43 × 53 = 0.01: the script brings each rail back 0.01 past its start.
        assert!(
            (t.top_row_return_error[c] - 0.01).abs() < 1e-9,
            "rail {c} ends {} from its start",
            t.top_row_return_error[c]
        );
    }
    assert_eq!(t.collisions_with_surfaces, 0, "no force leaves the planes, so no collision may fire");
    assert_eq!(t.max_out_of_plane, 0.0);
    // The report's E-6 search: not at rest by frame 145, and at the rate the swing decays in the pause
    // (frames 78–100) rest would take far longer than the 5 s the script leaves after the rails stop.
    let v = &t.max_speed;
    assert!(v[144] > 10.0 * flex3d::AT_REST_SPEED, "the curtains came to rest: {}", v[144]);
    let rest = flex3d::pause_rest_time(v[77], v[99], v[139]);
    assert!(rest > 20.0, "rest after frame 140 would take only {rest} s");
}

#[test]
fn e7_cardboard_is_smoother_than_paper() {
    let paper = flex3d::peeling_sheet(ThesisScene::Paper, FrictionMode::Literal, true).unwrap();
    let card = flex3d::peeling_sheet(ThesisScene::Cardboard, FrictionMode::Literal, true).unwrap();
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    let (c, p) = (mean(&card.mean_bend[2..15]), mean(&paper.mean_bend[2..15]));
    assert!(c < 0.5 * p, "cardboard mean bend {c} against paper {p}");
    let (c, p) = (mean(&card.max_bend[2..15]), mean(&paper.max_bend[2..15]));
    assert!(c < p, "cardboard sharpest fold {c} against paper {p}");
    assert!((card.corner[10].z - 18.0).abs() < 1.0, "corner z at frame 11: {}", card.corner[10].z);
}

#[test]
fn e8_tablecloth_never_enters_the_table() {
    for friction in [FrictionMode::Literal, FrictionMode::Viscous] {
        let e = flex3d::e8_tablecloth(friction).unwrap();
        assert_eq!(e.penetrations_total, 0, "{friction:?}: particles found inside the table");
        let t = e.first_contact_time.expect("the cloth reaches the table");
        assert!((1.5..=2.5).contains(&t), "{friction:?}: first contact at {t} s");
        if friction == FrictionMode::Viscous {
            // Under the viscous reading the cloth never comes to rest (fastest particle 58–62 m/s over
            // the run before and after the segment–triangle fix of the collision pass, 9.4 m/s at the
            // end after it), so where its centre happens to be at the end says nothing about draping:
            // it passed the checks below by chance before that fix (y = 10.69 after it).
            assert!(e.max_speed_last > 1.0, "the viscous reading came to rest: {}", e.max_speed_last);
            continue;
        }
        assert!(e.max_speed_last < 2.0, "{friction:?}: still moving at {} m/s", e.max_speed_last);
        assert!(
            (e.centre_y - 10.0).abs() < 0.5,
            "{friction:?}: the centre rests on the top: y = {}",
            e.centre_y
        );
        assert!(e.corner_y < 5.0, "{friction:?}: the corners drape down: y = {}", e.corner_y);
    }
}
