//! A small CPU ray tracer that embeds the 8-lane kernel: a flagstone floor,
//! a sphere of crumpled foil and a sphere of reptile hide, shaded in packets
//! of eight hits, on all cores.
//!
//! Each pixel's footprint on the surface it hits comes from ray
//! differentials, and the textures stand for that footprint
//! (`worley::filter`): fine octaves, stone colours, mortar lines and stains
//! fade towards their means where a pixel covers many cells, so the
//! horizon shows no moiré and costs less.
//!
//! ```sh
//! cargo run --release -p worley-cli --example render_scene -- [WIDTH HEIGHT] [PATH] [--point] [--spp N] [--cover] [--split]
//! cargo run --release -p worley-cli --example render_scene -- --campaign [WIDTH HEIGHT] [DIR]
//! ```
//!
//! `--point` point-samples the textures (one sample per pixel unless
//! `--spp` asks for more, on a stratified jittered grid); `--cover` gives
//! wide footprints the colours of the stones they cover, `--split` shades
//! the floor at four points of mid-sized footprints (both measured in the
//! campaign); `--campaign` renders the scene and a plane receding to the
//! horizon every way (point sampling, filtered with each option, 4, 16
//! and 64 samples per pixel) against a
//! 256-samples-per-pixel reference, prints the table of error against time
//! per frame, and writes the plot and the pictures into DIR (default
//! `out/footprint`).

mod campaign;
mod materials;
mod scene;
mod shading;

use std::time::Instant;

use crate::campaign::run_campaign;
use crate::materials::{Shading, Textures};
use crate::scene::{views, Width};
use crate::shading::{render, to_rgb, write};

fn main() -> Result<(), String> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut flag = |name: &str| args.iter().position(|a| a == name).map(|i| args.remove(i)).is_some();
    let point = flag("--point");
    let (cover, split) = (flag("--cover"), flag("--split"));
    let campaign = flag("--campaign");
    let spp = match args.iter().position(|a| a == "--spp") {
        Some(i) => {
            let n = args.get(i + 1).and_then(|s| s.parse::<usize>().ok()).filter(|&n| {
                let side = (n as f64).sqrt().round() as usize;
                (1..=1024).contains(&n) && side * side == n
            });
            args.drain(i..(i + 2).min(args.len()));
            n.ok_or("--spp takes a square number of samples per pixel from 1 to 1024")?
        }
        None => 1,
    };
    let number = |i: usize, default: usize| -> Result<usize, String> {
        args.get(i)
            .map_or(Ok(default), |s| s.parse().map_err(|_| format!("{s:?} is not a size: use WIDTH HEIGHT [PATH]")))
    };
    let (default_w, default_h) = if campaign { (640, 360) } else { (1280, 720) };
    let (width, height) = (number(0, default_w)?, number(1, default_h)?);
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err("use a size from 1x1 to 16384x16384".into());
    }
    if campaign {
        let dir = args.get(2).cloned().unwrap_or_else(|| "out/footprint".into());
        return run_campaign(width, height, std::path::Path::new(&dir));
    }
    let path = args.get(2).cloned().unwrap_or_else(|| "out/scene.png".into());
    let started = Instant::now();
    let textures = Textures::new();
    let built = started.elapsed().as_secs_f64();
    let [(_, world, camera), _] = views(width, height);
    let shading =
        if point || spp > 1 { Shading::Point } else { Shading::Filtered { width: Width::Area, cover, split } };
    let image = render(&textures, &world, &camera, shading, spp);
    let elapsed = started.elapsed().as_secs_f64();
    write(std::path::Path::new(&path), &to_rgb(&camera, &image).to_png()?)?;
    println!(
        "rendered {width}x{height} ({}, {spp} sample(s) per pixel) in {elapsed:.2} s (textures built in {built:.2} s) \
         on {} threads ({:.2} M pixels/s); wrote {path}",
        if shading == Shading::Point { "point-sampled textures" } else { "filtered textures" },
        rayon::current_num_threads(),
        (width * height) as f64 / (elapsed - built) / 1e6
    );
    Ok(())
}
