//! Pictures to look at by eye, not assertions:
//! `cargo test -p anima-viz --release -- --ignored --nocapture preview` writes them to
//! `anima-viz-preview/` in the system's temporary directory and prints the render times.

use std::time::Instant;

use anima_geom::{DVec3, box_mesh, grid_triangles};

use crate::{Camera, Image, LinePlot, RenderMesh, RenderSettings, Series, render};

/// A square sheet of side 2·`half` with n × n particles draped by formula over a table top of half-width
/// `a` at height `top`: flat on the top, rolling over the edge with radius `rho`, then hanging in folds.
fn draped_sheet(n: usize, half: f64, a: f64, top: f64) -> Vec<DVec3> {
    let rho = 0.05;
    let mut out = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let u = -half + 2.0 * half * j as f64 / (n - 1) as f64;
            let v = -half + 2.0 * half * i as f64 / (n - 1) as f64;
            let clamp = (u.clamp(-a, a), v.clamp(-a, a));
            let off = (u - clamp.0, v - clamp.1);
            let d = off.0.hypot(off.1);
            if d == 0.0 {
                out.push(DVec3::new(u, top + 0.01, v));
                continue;
            }
            let dir = (off.0 / d, off.1 / d);
            let (reach, drop) = if d < rho * std::f64::consts::FRAC_PI_2 {
                (rho * (d / rho).sin(), rho * (1.0 - (d / rho).cos()))
            } else {
                (rho, rho + d - rho * std::f64::consts::FRAC_PI_2)
            };
            // Folds grow as the cloth hangs further below the edge.
            let along = if dir.0.abs() > dir.1.abs() { clamp.1 } else { clamp.0 };
            let fold = 0.06 * (drop / 0.6).min(1.0) * (along * 14.0).sin();
            let r = reach + 0.01 + fold.max(-0.5 * reach);
            out.push(DVec3::new(clamp.0 + dir.0 * r, top + 0.01 - drop, clamp.1 + dir.1 * r));
        }
    }
    out
}

#[test]
#[ignore = "writes pictures for a person to look at"]
fn preview() {
    let dir = std::env::temp_dir().join("anima-viz-preview");
    std::fs::create_dir_all(&dir).unwrap();
    let save = |name: &str, img: &Image| {
        let path = dir.join(name);
        img.write_png(std::io::BufWriter::new(std::fs::File::create(&path).unwrap())).unwrap();
        println!("wrote {}", path.display());
    };

    // Cloth over a table.
    let table = box_mesh(DVec3::new(-0.5, 0.0, -0.5), DVec3::new(0.5, 0.75, 0.5));
    let n = 20;
    let sheet = draped_sheet(n, 0.9, 0.5, 0.75);
    let tris = grid_triangles(n, n);
    let scene = [
        RenderMesh::from_mesh(&table, [150, 110, 80]),
        RenderMesh::new(&sheet, &tris, [200, 70, 60]).with_edges(),
    ];
    let aabb = table.aabb().union(anima_geom::Aabb::from_points(sheet.iter().copied()));
    let camera = Camera::framing(aabb, DVec3::new(-0.8, -0.6, -1.0), DVec3::Y, 35.0);
    let settings = RenderSettings::new(800, 600);
    let t0 = Instant::now();
    let img = render(&scene, &camera, &settings).unwrap();
    println!("draped sheet 20×20: {:?}", t0.elapsed());
    save("draped_sheet.png", &img);

    // Low and orthographic views: the horizon shows, and parallel edges stay parallel.
    let low = Camera::framing(aabb, DVec3::new(-1.0, -0.12, -0.6), DVec3::Y, 50.0);
    let ortho = Camera::framing_orthographic(aabb, DVec3::new(-1.0, -1.0, -1.0), DVec3::Y);
    let small = RenderSettings::new(400, 300);
    let views = [render(&scene, &low, &small).unwrap(), render(&scene, &ortho, &small).unwrap()];
    save("low_and_orthographic.png", &Image::grid(&views, 2, 4, [255, 255, 255]).unwrap());

    // A fine sheet: about 100k triangles.
    let n = 224;
    let fine = draped_sheet(n, 0.9, 0.5, 0.75);
    let fine_tris = grid_triangles(n, n);
    let scene = [
        RenderMesh::from_mesh(&table, [150, 110, 80]),
        RenderMesh::new(&fine, &fine_tris, [70, 110, 190]).with_edges(),
    ];
    let t0 = Instant::now();
    let img = render(&scene, &camera, &settings).unwrap();
    println!("draped sheet {} triangles: {:?}", fine_tris.len(), t0.elapsed());
    save("draped_sheet_fine.png", &img);

    // A 3×3 strip of labelled frames from different directions.
    let mut frames = Vec::new();
    for k in 0..9 {
        let angle = k as f64 * 0.7;
        let view = DVec3::new(-angle.cos(), -0.5, -angle.sin());
        let camera = Camera::framing(aabb, view, DVec3::Y, 35.0);
        let scene = [
            RenderMesh::from_mesh(&table, [150, 110, 80]),
            RenderMesh::new(&sheet, &tris, [200, 70, 60]).with_edges(),
        ];
        let mut frame = render(&scene, &camera, &RenderSettings::new(240, 180)).unwrap();
        frame.label(8, 6, &format!("t = {:.1} s", k as f64 * 0.5), 16.0).unwrap();
        frames.push(frame);
    }
    save("frames_3x3.png", &Image::grid(&frames, 3, 6, [255, 255, 255]).unwrap());

    // Position against time for six step sizes and the exact solution.
    let mut plot = LinePlot::new("Harmonic oscillator, forward Euler", "t [s]", "x [m]");
    for (k, h) in [0.5, 0.2, 0.1, 0.05, 0.02, 0.01].into_iter().enumerate() {
        let (mut x, mut v, mut pts) = (4.0f64, 0.0f64, Vec::new());
        let steps = (12.0 / h) as usize;
        for i in 0..=steps {
            pts.push((i as f64 * h, x));
            let a = -(x - 2.0);
            x += h * v;
            v += h * a;
        }
        let series = if k == 0 {
            Series::line_with_markers(format!("h = {h}"), pts)
        } else {
            Series::line(format!("h = {h}"), pts)
        };
        plot.series.push(series);
    }
    let exact = (0..=600).map(|i| i as f64 * 0.02).map(|t| (t, 2.0 + 2.0 * t.cos())).collect();
    plot.series.push(Series::dashed("exact 2 + 2 cos t", exact).with_colour([0, 0, 0]));
    plot.y_range = Some((-3.0, 7.0));
    save("plot_oscillator.png", &plot.render(800, 600).unwrap());

    // Work–precision on log–log axes.
    let mut wp = LinePlot::new("Work–precision", "function evaluations", "max error");
    wp.log_x = true;
    wp.log_y = true;
    for (name, order) in [("forward Euler", 1), ("RK2", 2), ("RK4", 4)] {
        let pts =
            (1..12).map(|k| 10f64.powf(1.0 + 0.35 * k as f64)).map(|n| (n, 5.0 * n.powi(-order))).collect();
        wp.series.push(Series::line_with_markers(name, pts));
    }
    save("plot_work_precision.png", &wp.render(800, 600).unwrap());
}
