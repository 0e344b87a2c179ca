//! The footprint campaign: every shading option against a
//! 256-samples-per-pixel reference, error against time per frame, and the
//! plot.

use std::time::Instant;

use crate::materials::{Shading, Textures};
use crate::scene::{views, Camera, Material, Width, World};
use crate::shading::{render, to_rgb, tone, write};
use glam::Vec3;
use rayon::prelude::*;
use worley_cli::picture::{to_byte, Rgb};

/// One way of rendering in the campaign.
pub(crate) struct Method {
    pub(crate) name: &'static str,
    /// The plot's label, and where it sits from the point (pixels), so the
    /// labels of nearby points do not overlap.
    pub(crate) label: (&'static str, i32, i32),
    pub(crate) shading: Shading,
    pub(crate) spp: usize,
}

/// A point of the plot: the view, the method's label, milliseconds per
/// frame and RMS error.
pub(crate) type Plotted = (&'static str, (&'static str, i32, i32), f64, f64);

/// What a method's frame measured.
pub(crate) struct Measured {
    pub(crate) seconds: f64,
    pub(crate) rms: f64,
    pub(crate) floor_rms: f64,
    pub(crate) high: f64,
}

/// Error of a frame against the reference, in tone-mapped [0, 1] values:
/// RMS over every pixel and channel, over the pixels whose every reference
/// sample met the floor (texture alone, no edges of geometry), and the
/// RMS of the error's high frequencies (the error minus its 5 × 5 box
/// average: moiré and salt-and-pepper noise, not a smooth bias).
pub(crate) fn errors(
    image: &[Vec3],
    reference: &[Vec3],
    floor_only: &[bool],
    width: usize,
    height: usize,
) -> (f64, f64, f64) {
    let diff: Vec<[f64; 3]> = image
        .iter()
        .zip(reference)
        .map(|(a, b)| {
            let (a, b) = (tone(*a), tone(*b));
            std::array::from_fn(|c| f64::from(a[c] - b[c]))
        })
        .collect();
    let sq = |d: &[f64; 3]| d.iter().map(|v| v * v).sum::<f64>() / 3.0;
    let rms = (diff.iter().map(sq).sum::<f64>() / diff.len() as f64).sqrt();
    let (mut fs, mut fc) = (0.0, 0usize);
    for (d, &f) in diff.iter().zip(floor_only) {
        if f {
            fs += sq(d);
            fc += 1;
        }
    }
    let mut high = 0.0;
    for y in 0..height {
        for x in 0..width {
            let mut mean = [0.0; 3];
            let mut count = 0.0;
            for yy in y.saturating_sub(2)..(y + 3).min(height) {
                for xx in x.saturating_sub(2)..(x + 3).min(width) {
                    for c in 0..3 {
                        mean[c] += diff[yy * width + xx][c];
                    }
                    count += 1.0;
                }
            }
            let d = diff[y * width + x];
            high += (0..3).map(|c| (d[c] - mean[c] / count).powi(2)).sum::<f64>() / 3.0;
        }
    }
    (rms, (fs / fc.max(1) as f64).sqrt(), (high / (width * height) as f64).sqrt())
}

pub(crate) fn run_campaign(width: usize, height: usize, dir: &std::path::Path) -> Result<(), String> {
    let started = Instant::now();
    let textures = Textures::new();
    println!(
        "textures and blend curves built in {:.2} s; {width}x{height}, {} threads",
        started.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    // The weights the floor's fields and F1 (the crumple's first octave) get
    // at a sixteenth of a unit and at one unit, and where they reach 0.
    for (name, curve) in [
        ("stone identity", &textures.identity),
        ("mortar", &textures.mortar),
        ("bevel", &textures.bevel),
        ("stains", &textures.stains),
        ("F1", textures.crumple.blend_curve()),
    ] {
        println!(
            "blend curve {name}: weight {:.3} at 1/16, {:.3} at 1, 0 from {:.3} (texture units)",
            curve.weight(0.0625),
            curve.weight(1.0),
            curve.cutoff()
        );
    }
    let methods = [
        Method { name: "(a) point sampling, 1 spp", label: ("a", 8, -5), shading: Shading::Point, spp: 1 },
        Method {
            name: "(b) filtered, 1 spp (area width)",
            label: ("b", -16, -5),
            shading: Shading::Filtered { width: Width::Area, cover: false, split: false },
            spp: 1,
        },
        Method {
            name: "(b) filtered, 1 spp (area width and cell cover)",
            label: ("b, cover", 8, 2),
            shading: Shading::Filtered { width: Width::Area, cover: true, split: false },
            spp: 1,
        },
        Method {
            name: "(b) filtered, 1 spp (area width and 4 floor sub-samples)",
            label: ("b, 4 floor sub-samples", 8, -5),
            shading: Shading::Filtered { width: Width::Area, cover: false, split: true },
            spp: 1,
        },
        Method {
            name: "(b') filtered, 1 spp (major-axis width)",
            label: ("b'", -4, -18),
            shading: Shading::Filtered { width: Width::Major, cover: false, split: false },
            spp: 1,
        },
        Method { name: "(c) point sampling, 4 spp", label: ("4 spp", 8, -5), shading: Shading::Point, spp: 4 },
        Method { name: "(c) point sampling, 16 spp", label: ("16 spp", 8, -5), shading: Shading::Point, spp: 16 },
        Method { name: "(c) point sampling, 64 spp", label: ("64 spp", 8, -5), shading: Shading::Point, spp: 64 },
    ];
    let mut table = String::from(
        "| view | method | ms per frame | RMS error | RMS error, floor pixels | high-frequency RMS error |\n|---|---|---|---|---|---|\n",
    );
    let mut plotted: Vec<Plotted> = Vec::new();
    for (view, world, camera) in views(width, height) {
        let t = Instant::now();
        let reference = render(&textures, &world, &camera, Shading::Point, 256);
        let reference_ms = t.elapsed().as_secs_f64() * 1e3;
        // Pixels whose reference samples all met the floor: the reference at
        // 256 samples, with the floor's colour replaced by a flag.
        let floor_only: Vec<bool> = floor_pixels(&world, &camera);
        write(&dir.join(format!("{view}_reference.png")), &to_rgb(&camera, &reference).to_png()?)?;
        // Every method renders once; then the cheap ones (up to 4 spp) four
        // more times, round-robin, so a slow spell of the machine falls on
        // all of them alike. A frame's time is the median of its runs.
        let mut images: Vec<Vec<Vec3>> = Vec::new();
        let mut times: Vec<Vec<f64>> = vec![Vec::new(); methods.len()];
        for round in 0..5 {
            for (i, m) in methods.iter().enumerate() {
                if round > 0 && m.spp > 4 {
                    continue;
                }
                let t = Instant::now();
                let image = render(&textures, &world, &camera, m.shading, m.spp);
                times[i].push(t.elapsed().as_secs_f64());
                if round == 0 {
                    images.push(image);
                }
            }
        }
        for ((m, image), times) in methods.iter().zip(&images).zip(&mut times) {
            times.sort_by(f64::total_cmp);
            let seconds = times[times.len() / 2];
            let (rms, floor_rms, high) = errors(image, &reference, &floor_only, width, height);
            let r = Measured { seconds, rms, floor_rms, high };
            table += &format!(
                "| {view} | {} | {:.1} | {:.4} | {:.4} | {:.4} |\n",
                m.name,
                r.seconds * 1e3,
                r.rms,
                r.floor_rms,
                r.high
            );
            plotted.push((view, m.label, r.seconds * 1e3, r.rms));
            if m.spp == 1 {
                let tag = match m.shading {
                    Shading::Point => "point",
                    Shading::Filtered { width: Width::Major, .. } => "filtered_major",
                    Shading::Filtered { cover: true, .. } => "filtered_cover",
                    Shading::Filtered { split: true, .. } => "filtered_split",
                    Shading::Filtered { .. } => "filtered",
                };
                write(&dir.join(format!("{view}_{tag}.png")), &to_rgb(&camera, image).to_png()?)?;
                // The error, eight times brighter.
                let error = Rgb {
                    width,
                    height,
                    pixels: image
                        .iter()
                        .zip(&reference)
                        .map(|(a, b)| {
                            let (a, b) = (tone(*a), tone(*b));
                            std::array::from_fn(|c| to_byte(8.0 * (a[c] - b[c]).abs()))
                        })
                        .collect(),
                };
                write(&dir.join(format!("{view}_{tag}_error.png")), &error.to_png()?)?;
            }
        }
        table += &format!("| {view} | reference, point sampling, 256 spp | {reference_ms:.1} | 0 | 0 | 0 |\n");
    }
    println!("{table}");
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    write(&dir.join("table.md"), table.as_bytes())?;
    write(&dir.join("error_against_time.svg"), plot(&plotted)?.as_bytes())?;
    println!("wrote the pictures, table.md and error_against_time.svg into {}", dir.display());
    Ok(())
}

/// Per pixel, whether all 256 reference samples meet the floor.
pub(crate) fn floor_pixels(world: &World, camera: &Camera) -> Vec<bool> {
    let side = 16;
    (0..camera.width * camera.height)
        .into_par_iter()
        .map(|p| {
            let (x, y) = (p % camera.width, p / camera.width);
            (0..side * side).all(|k| {
                let (sx, sy) = ((k % side) as f32 + 0.5, (k / side) as f32 + 0.5);
                let d = camera.ray(x as f32 + sx / side as f32, y as f32 + sy / side as f32).normalize();
                world.trace(camera.eye, d).material == Material::Floor
            })
        })
        .collect()
}

/// RMS error against milliseconds per frame, log-log, one series per view.
pub(crate) fn plot(points: &[Plotted]) -> Result<String, String> {
    use plotters::prelude::*;
    let fail = |e: &dyn std::fmt::Display| format!("cannot draw the plot: {e}");
    let (x_lo, x_hi) = points.iter().fold((f64::MAX, 0f64), |(l, h), p| (l.min(p.2), h.max(p.2)));
    let (y_lo, y_hi) = points.iter().fold((f64::MAX, 0f64), |(l, h), p| (l.min(p.3), h.max(p.3)));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (820, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Error against the 256-spp reference, by time per frame", ("sans-serif", 16))
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d((x_lo / 1.5..x_hi * 1.5).log_scale(), (y_lo / 1.5..y_hi * 1.5).log_scale())
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .y_label_formatter(&|v| format!("{v:.3}"))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .x_desc("milliseconds per frame")
            .y_desc("RMS error (tone-mapped, 0..1)")
            .draw()
            .map_err(|e| fail(&e))?;
        for (view, colour) in [("scene", RGBColor(36, 113, 163)), ("plane", RGBColor(192, 57, 43))] {
            let series: Vec<_> = points.iter().filter(|p| p.0 == view).collect();
            chart
                .draw_series(series.iter().map(|p| Circle::new((p.2, p.3), 5, colour.filled())))
                .map_err(|e| fail(&e))?
                .label(view)
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
            chart
                .draw_series(series.iter().map(|p| {
                    let (label, dx, dy) = p.1;
                    EmptyElement::at((p.2, p.3))
                        + Text::new(label.to_string(), (dx, dy), ("sans-serif", 11).into_font())
                }))
                .map_err(|e| fail(&e))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE)
            .border_style(BLACK)
            .draw()
            .map_err(|e| fail(&e))?;
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(svg)
}
