//! The `worley` command: `render` writes a PNG of the requested size and a
//! PFM holding the library's values at the documented pixel positions; bad
//! options get one line and exit code 2; an unwritable output leaves nothing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use worley::texture::{Combination, Fractal, Texture};
use worley::{Config, Metric, Period, SimdBorder};
use worley_cli::picture::from_pfm;

fn worley(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_worley")).args(args).output().expect("the worley binary runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("worley-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn png_size(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().expect("a PNG header");
    let mut buf = vec![0; reader.output_buffer_size().expect("a sane size")];
    let info = reader.next_frame(&mut buf).expect("PNG data decodes");
    (info.width, info.height)
}

/// Pixel (i, j) samples axes 0 and 1 at (origin + ½·step) + (i, j)·step with
/// step = extent / width (the documentation of `worley_cli::views`).
fn pixel(origin: [f64; 2], extent: f64, width: usize, i: usize, j: usize) -> [f64; 2] {
    let step = extent / width as f64;
    [origin[0] + 0.5 * step + step * i as f64, origin[1] + 0.5 * step + step * j as f64]
}

#[test]
fn render_writes_the_requested_png_and_the_librarys_values() {
    let dir = scratch("render");
    let (png, pfm) = (dir.join("crackle.png"), dir.join("crackle.pfm"));
    let out = worley(&[
        "render",
        "--dim",
        "3",
        "--combo",
        "F2-F1",
        "--metric",
        "manhattan",
        "--size",
        "37x23",
        "--extent",
        "5",
        "--origin",
        "1.5,-2",
        "--slice",
        "0.25",
        "--seed",
        "7",
        "--octaves",
        "2",
        "--png",
        png.to_str().unwrap(),
        "--pfm",
        pfm.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(png_size(&png), (37, 23));
    let (w, h, values) = from_pfm(&std::fs::read(&pfm).unwrap()).unwrap();
    assert_eq!((w, h), (37, 23));
    let config = Config { seed: 7, metric: Metric::Manhattan, ..Config::default() };
    let texture = Texture::<3, 2>::new(config, Combination::crackle(), Fractal::octaves(2), None).unwrap();
    for j in 0..h {
        for i in 0..w {
            let [x, y] = pixel([1.5, -2.0], 5.0, w, i, j);
            let want = texture.value([x, y, 0.25]);
            assert_eq!(values[j * w + i].to_bits(), want.to_bits(), "pixel ({i}, {j})");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_filtered_render_holds_the_librarys_footprint_values() {
    // A step of 8 units: the fine octaves are unresolved, so the filtered
    // values differ from the point samples, and each is the library's
    // value for a footprint one step wide.
    let dir = scratch("filtered");
    let pfm = dir.join("filtered.pfm");
    let out = worley(&[
        "render",
        "--dim",
        "2",
        "--combo",
        "F1",
        "--octaves",
        "4",
        "--size",
        "24x16",
        "--extent",
        "192",
        "--filtered",
        "--png",
        dir.join("filtered.png").to_str().unwrap(),
        "--pfm",
        pfm.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (w, h, values) = from_pfm(&std::fs::read(&pfm).unwrap()).unwrap();
    assert_eq!((w, h), (24, 16));
    let texture = Texture::<2, 1>::new(Config::default(), Combination::f(1), Fractal::octaves(4), None).unwrap();
    let mut differ = 0;
    for j in 0..h {
        for i in 0..w {
            let x = pixel([0.0, 0.0], 192.0, w, i, j);
            let want = texture.filtered(x, 8.0);
            assert_eq!(values[j * w + i].to_bits(), want.to_bits(), "pixel ({i}, {j})");
            differ += usize::from(want != texture.value(x));
        }
    }
    assert_eq!(differ, w * h, "every pixel's footprint spans cells");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_periodic_render_tiles_and_matches_the_library() {
    let dir = scratch("tile");
    let pfm = dir.join("tile.pfm");
    let out = worley(&[
        "render",
        "--dim",
        "2",
        "--combo",
        "F1",
        "--period",
        "4,4",
        "--extent",
        "8",
        "--size",
        "32x32",
        "--png",
        dir.join("tile.png").to_str().unwrap(),
        "--pfm",
        pfm.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (w, _, values) = from_pfm(&std::fs::read(&pfm).unwrap()).unwrap();
    let texture = Texture::<2, 1>::new(
        Config::default(),
        Combination::f(1),
        Fractal::default(),
        Some(Period::new([4, 4]).unwrap()),
    )
    .unwrap();
    for j in 0..32 {
        for i in 0..32 {
            let v = values[j * w + i];
            assert_eq!(v.to_bits(), texture.value(pixel([0.0, 0.0], 8.0, w, i, j)).to_bits());
            // Eight cells across: the pixel four cells on is the same value.
            if i < 16 && j < 16 {
                assert_eq!(v.to_bits(), values[(j + 16) * w + i + 16].to_bits());
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--combo border`: the distance to the cell's border, as the library's
/// lanes compute it on a periodic tile, bit for bit; other metrics are
/// refused with the reason.
#[test]
fn a_border_render_matches_the_library_and_refuses_other_metrics() {
    let dir = scratch("border");
    let pfm = dir.join("border.pfm");
    let out = worley(&[
        "render",
        "--dim",
        "2",
        "--combo",
        "border",
        "--period",
        "4,4",
        "--extent",
        "8",
        "--size",
        "32x32",
        "--png",
        dir.join("border.png").to_str().unwrap(),
        "--pfm",
        pfm.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (w, _, values) = from_pfm(&std::fs::read(&pfm).unwrap()).unwrap();
    let border = SimdBorder::<2>::new(Config::default()).unwrap();
    let period = Period::new([4, 4]).unwrap();
    for j in 0..32 {
        for i in 0..32 {
            let want = border.border_periodic(pixel([0.0, 0.0], 8.0, w, i, j), &period).distance;
            assert_eq!(values[j * w + i].to_bits(), want.to_bits(), "pixel ({i}, {j})");
        }
    }
    let refused = worley(&["render", "--combo", "border", "--metric", "chebyshev", "--png", "-"]);
    assert!(!refused.status.success());
    let said = String::from_utf8_lossy(&refused.stderr);
    assert!(said.contains("Euclidean"), "{said}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--combo smooth:S`: compact smooth F1 as the library's lanes compute it,
/// bit for bit; a bad smoothness and other metrics are refused with one
/// line and exit code 2.
#[test]
fn a_smooth_render_matches_the_library_and_refuses_what_it_cannot_do() {
    let dir = scratch("smooth");
    let pfm = dir.join("smooth.pfm");
    let args =
        ["render", "--dim", "2", "--combo", "smooth:0.3", "--extent", "8", "--size", "32x32", "--png", "-", "--pfm"];
    let out = worley(&[&args[..], &[pfm.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (w, _, values) = from_pfm(&std::fs::read(&pfm).unwrap()).unwrap();
    let smooth = worley::SimdSmooth::<2>::new(Config::default()).unwrap();
    for j in 0..32 {
        for i in 0..32 {
            let want = smooth.smooth(pixel([0.0, 0.0], 8.0, w, i, j), 0.3).value;
            assert_eq!(values[j * w + i].to_bits(), want.to_bits(), "pixel ({i}, {j})");
        }
    }
    for (bad, words) in [
        (&["--combo", "smooth:-1"][..], "smoothness"),
        (&["--combo", "smooth:0.3", "--metric", "manhattan"][..], "Euclidean"),
    ] {
        let refused = worley(&[&["render", "--png", "-"][..], bad].concat());
        assert_eq!(refused.status.code(), Some(2), "{bad:?}");
        let said = String::from_utf8_lossy(&refused.stderr);
        assert!(said.contains(words) && said.trim().lines().count() == 1, "{bad:?}: {said}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--combo n-sphere`: the n-sphere radius as the library's lanes compute
/// it, bit for bit, periodic with `--period`; other metrics are refused.
#[test]
fn an_n_sphere_render_matches_the_library_and_tiles() {
    let dir = scratch("n-sphere");
    let pfm = dir.join("spheres.pfm");
    let args = [
        "render", "--dim", "2", "--combo", "n-sphere", "--period", "4,4", "--extent", "8", "--size", "32x32", "--png",
        "-", "--pfm",
    ];
    let out = worley(&[&args[..], &[pfm.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (w, _, values) = from_pfm(&std::fs::read(&pfm).unwrap()).unwrap();
    let spheres = worley::SimdNSphere::<2>::new(Config::default()).unwrap();
    let period = Period::new([4, 4]).unwrap();
    for j in 0..32 {
        for i in 0..32 {
            let want = spheres.n_sphere_periodic(pixel([0.0, 0.0], 8.0, w, i, j), &period).radius;
            assert_eq!(values[j * w + i].to_bits(), want.to_bits(), "pixel ({i}, {j})");
        }
    }
    let refused = worley(&["render", "--combo", "n-sphere", "--metric", "manhattan", "--png", "-"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("Euclidean"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn random_combinations_print_their_coefficients() {
    let dir = scratch("combos");
    let png = dir.join("sheet.png");
    let out = worley(&[
        "render",
        "--random-combos",
        "5",
        "--combo-seed",
        "3",
        "--size",
        "16x16",
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.lines().filter(|l| l.contains("C = [")).count(), 5, "{text}");
    // Three columns of 16 pixels with 2-pixel gaps, two rows.
    assert_eq!(png_size(&png), (52, 34));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_options_get_one_line_and_exit_code_2() {
    let cases: [(&[&str], &str); 15] = [
        (&["render", "--bogus"], "unexpected argument"),
        (&["render", "--size", "8x8", "--region", "4,4,5,2", "--png", "-"], "outside the 8x8 image"),
        (&["render", "--region", "1,2,0,3"], "X,Y,W,H"),
        (&["render", "--tile", "3/3"], "0 <= I < N"),
        (&["render", "--tile", "0/0"], "0 <= I < N"),
        (&["render", "--size", "8x4", "--tile", "0/5", "--png", "-"], "at most the image's height (4)"),
        (&["render", "--exr", "-", "--channels", "F1,colour"], "unknown channel \"colour\""),
        (&["render", "--depth", "2", "--dim", "2", "--png", "-"], "need --dim 3 or 4"),
        (&["stitch", "--out", "-", "/nonexistent/a.exr"], "cannot read /nonexistent/a.exr"),
        (&["render", "--size", "0x4"], "WIDTHxHEIGHT"),
        (&["render", "--shade", "shiny"], "possible values"),
        (&["render", "--combo", "F2+G1"], "F1*F2"),
        (&["render", "--octaves", "60"], "not resolved in f32"),
        (&["check", "--metric", "minkowski:0.5"], "p >= 1"),
        (&["tune", "--orders", "3"], "use 1, 2, 4 or 8"),
    ];
    for (args, words) in cases {
        let out = worley(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(words), "{args:?}: {err:?} should say {words:?}");
    }
}

#[test]
fn an_unwritable_output_is_an_error_and_leaves_no_file() {
    let dir = scratch("unwritable");
    // The PNG's target is an existing folder: the final rename fails.
    let taken = dir.join("taken.png");
    std::fs::create_dir_all(taken.join("inside")).unwrap();
    let out = worley(&["render", "--size", "8x8", "--png", taken.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8(out.stderr).unwrap().contains("cannot write"));
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left, vec![std::ffi::OsString::from("taken.png")]);
    std::fs::remove_dir_all(&dir).unwrap();
}

const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

#[test]
fn outputs_follow_symlinks_and_write_special_files_directly() {
    use std::os::unix::fs::{symlink, FileTypeExt};
    let dir = scratch("paths");
    let args = |png: &Path| -> Vec<String> {
        ["render", "--size", "16x8", "--png"].iter().map(|s| s.to_string()).chain([png.display().to_string()]).collect()
    };
    let run = |png: &Path| {
        let a = args(png);
        worley(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };

    // A chain of two links, one relative: the links stay links, the
    // target gets the image.
    std::fs::create_dir_all(dir.join("real")).unwrap();
    std::fs::write(dir.join("real/target.png"), b"old").unwrap();
    symlink("real/target.png", dir.join("first.png")).unwrap();
    symlink(dir.join("first.png"), dir.join("second.png")).unwrap();
    let out = run(&dir.join("second.png"));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::symlink_metadata(dir.join("second.png")).unwrap().file_type().is_symlink());
    assert!(std::fs::symlink_metadata(dir.join("first.png")).unwrap().file_type().is_symlink());
    assert!(std::fs::read(dir.join("real/target.png")).unwrap().starts_with(PNG_SIGNATURE));

    // A FIFO is written through, not replaced by a regular file.
    let fifo = dir.join("pipe.png");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap())
    };
    let out = run(&fifo);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(reader.join().unwrap().starts_with(PNG_SIGNATURE));
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());

    // `-` is standard output.
    let out = run(Path::new("-"));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stdout.starts_with(PNG_SIGNATURE));
    assert!(!Path::new("-").exists());

    // A link into a folder that does not exist: one line, exit code 2.
    symlink(dir.join("nowhere/x.png"), dir.join("dangling.png")).unwrap();
    let out = run(&dir.join("dangling.png"));
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.starts_with("worley: cannot write") && err.lines().count() == 1, "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An EXR file's channels: (layer name, channel name) to the layer's data
/// window (position, size) and samples.
type Channels = std::collections::BTreeMap<(Option<String>, String), ([i32; 2], [usize; 2], exr::prelude::FlatSamples)>;

fn read_exr(path: &Path) -> (exr::prelude::IntegerBounds, Channels, Vec<exr::prelude::LayerAttributes>) {
    use exr::prelude::{ReadChannels as _, ReadLayers as _};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .expect("an EXR the exr crate reads");
    let mut channels = Channels::new();
    let mut attributes = Vec::new();
    for layer in image.layer_data {
        let name = layer.attributes.layer_name.as_ref().map(|n| n.to_string());
        let (pos, size) = (layer.attributes.layer_position, layer.size);
        for c in layer.channel_data.list {
            channels.insert((name.clone(), c.name.to_string()), ([pos.0, pos.1], [size.0, size.1], c.sample_data));
        }
        attributes.push(layer.attributes);
    }
    (image.attributes.display_window, channels, attributes)
}

fn f32s(s: &exr::prelude::FlatSamples) -> &[f32] {
    match s {
        exr::prelude::FlatSamples::F32(v) => v,
        _ => panic!("a float channel"),
    }
}

/// Every channel of a 3D bake of two planes, read back with the exr crate,
/// is the library's value at the pixel's point, bit for bit: the texture
/// (filtered, three octaves), F1, F2, F2 − F1, F1's ID (as u32) and delta,
/// the border and the bump normal; the header holds the configuration.
#[test]
fn an_exr_bake_holds_the_librarys_values_in_every_channel() {
    let dir = scratch("exr");
    let exr = dir.join("bake.exr");
    let (w, h, extent, origin, z) = (23usize, 13usize, 3.0, [0.5, -1.0], 0.25);
    let out = worley(&[
        "render",
        "--dim",
        "3",
        "--combo",
        "F2-F1",
        "--size",
        "23x13",
        "--extent",
        "3",
        "--origin",
        "0.5,-1",
        "--slice",
        "0.25",
        "--seed",
        "11",
        "--octaves",
        "3",
        "--filtered",
        "--shade",
        "bump",
        "--depth",
        "2",
        "--channels",
        "all",
        "--png",
        dir.join("bake.png").to_str().unwrap(),
        "--exr",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (display, channels, attributes) = read_exr(&exr);
    assert_eq!((display.size.0, display.size.1), (w, h));
    let names: Vec<&str> = channels.keys().filter(|k| k.0.as_deref() == Some("z0001")).map(|k| k.1.as_str()).collect();
    let want = [
        "F1", "F2", "F2-F1", "border", "delta.X", "delta.Y", "delta.Z", "id", "normal.X", "normal.Y", "normal.Z",
        "value",
    ];
    assert_eq!(names, want);
    // One attribute with the settings, the same in every plane but for z.
    let settings = |a: &exr::prelude::LayerAttributes| match a.other.get(&exr::prelude::Text::from("worley")) {
        Some(exr::prelude::AttributeValue::Text(t)) => t.to_string(),
        other => panic!("the worley attribute is text: {other:?}"),
    };
    assert_eq!(attributes.len(), 2);
    let first = settings(&attributes[0]);
    let combination = format!("; combination={}; ", Combination::crackle().name());
    for want in ["; seed=11; ", &combination, "; octaves=3; ", "; filtered=true; ", "; slice=0.25,0.25; ", "; z=0.25"] {
        assert!(first.contains(want), "{first:?} should hold {want:?}");
    }
    let z1 = format!("; z={}", z + extent / w as f64);
    assert!(settings(&attributes[1]).ends_with(&z1), "{}", settings(&attributes[1]));

    let config = Config { seed: 11, ..Config::default() };
    let texture = Texture::<3, 2>::new(config, Combination::crackle(), Fractal::octaves(3), None).unwrap();
    let basis = worley::Simd::<3, 2>::new(Config { order: 2, ..config }, worley::Outputs::IdsAndDeltas).unwrap();
    let border = SimdBorder::<3>::new(config).unwrap();
    let step = extent / w as f64;
    for plane in 0..2usize {
        let layer = Some(format!("z{plane:04}"));
        let get = |name: &str| &channels[&(layer.clone(), name.to_string())].2;
        let ids = match get("id") {
            exr::prelude::FlatSamples::U32(v) => v.clone(),
            _ => panic!("the ID is a u32 channel"),
        };
        for j in 0..h {
            for i in 0..w {
                let [x, y] = pixel(origin, extent, w, i, j);
                let p = [x, y, z + step * plane as f64];
                let k = j * w + i;
                let bits = |name: &str| f32s(get(name))[k].to_bits();
                assert_eq!(bits("value"), texture.filtered(p, step as f32).to_bits(), "value at {p:?}");
                let f = basis.evaluate(p);
                assert_eq!(bits("F1"), f.distance[0].to_bits());
                assert_eq!(bits("F2"), f.distance[1].to_bits());
                assert_eq!(bits("F2-F1"), (f.distance[1] - f.distance[0]).to_bits());
                assert_eq!(ids[k], f.id[0]);
                for (a, axis) in ["X", "Y", "Z"].iter().enumerate() {
                    assert_eq!(bits(&format!("delta.{axis}")), f.delta[0][a].to_bits());
                }
                assert_eq!(bits("border"), border.border(p).distance.to_bits());
                let g = texture.filtered_gradient8(&[p; 8], [step as f32; 8]);
                let gradient = glam::Vec3::new(g.gradient[0].to_array()[0], g.gradient[1].to_array()[0], 0.0);
                let normal = worley::texture::bump(glam::Vec3::Z, gradient, 0.6);
                assert_eq!(bits("normal.Z"), normal.z.to_bits(), "normal at {p:?}");
                assert_eq!(bits("normal.X"), normal.x.to_bits());
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Bands of `--tile` and windows of `--region`, baked by separate runs and
/// stitched, are the whole image's EXR bit for bit (a periodic 2D texture,
/// whose channels take eight points at a time, and a 3D fractal whose value
/// and basis take whole grid rows, beside the border); stitch refuses
/// overlapping and missing windows.
#[test]
fn tiles_and_regions_stitch_into_the_whole_exr() {
    let dir = scratch("stitch");
    let cases: [&[&str]; 2] = [
        &["--dim", "2", "--period", "5", "--extent", "5", "--combo", "F1", "--channels", "value,F1,F2,id,delta"],
        &[
            "--dim",
            "3",
            "--combo",
            "F2-F1",
            "--octaves",
            "3",
            "--extent",
            "4",
            "--origin=-3.5,7",
            "--channels",
            "value,F2-F1,border,id",
        ],
    ];
    for (c, case) in cases.iter().enumerate() {
        let run = |name: &str, window: &[&str]| {
            let path = dir.join(format!("{c}-{name}.exr"));
            let mut args = vec!["render", "--size", "41x19", "--range", "0,1", "--png", "-", "--exr"];
            let path_str = path.to_str().unwrap().to_string();
            args.push(&path_str);
            args.extend_from_slice(case);
            args.extend_from_slice(window);
            let out = worley(&args);
            assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
            path
        };
        let whole = run("whole", &[]);
        let tiles: Vec<PathBuf> = (0..3).map(|i| run(&format!("tile{i}"), &["--tile", &format!("{i}/3")])).collect();
        let regions = [
            run("left", &["--region", "0,0,17,19"]),
            run("top-right", &["--region", "17,0,24,6"]),
            run("bottom-right", &["--region", "17,6,24,13"]),
        ];
        let (_, want, _) = read_exr(&whole);
        for (label, parts) in [("tiles", &tiles[..]), ("regions", &regions[..])] {
            let stitched = dir.join(format!("{c}-{label}.exr"));
            let mut args = vec!["stitch".to_string(), "--out".into(), stitched.display().to_string()];
            args.extend(parts.iter().rev().map(|p| p.display().to_string()));
            let out = Command::new(env!("CARGO_BIN_EXE_worley")).args(&args).output().unwrap();
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            // The same settings give the same bytes: the stitched file is
            // the whole image's file.
            assert!(std::fs::read(&stitched).unwrap() == std::fs::read(&whole).unwrap(), "case {c}, {label}");
            let (display, got, _) = read_exr(&stitched);
            assert_eq!((display.size.0, display.size.1), (41, 19));
            assert_eq!(got.keys().collect::<Vec<_>>(), want.keys().collect::<Vec<_>>(), "{label}");
            for (key, (_, size, samples)) in &got {
                assert_eq!(*size, [41, 19]);
                let same = match (samples, &want[key].2) {
                    (exr::prelude::FlatSamples::F32(a), exr::prelude::FlatSamples::F32(b)) => {
                        a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
                    }
                    (a, b) => a == b,
                };
                assert!(same, "case {c}, {label}: channel {key:?} differs from the whole image's");
            }
        }
        // A band twice, or one left out: refused with the reason.
        let stitch = |files: &[&PathBuf]| {
            let mut args = vec!["stitch".to_string(), "--out".into(), dir.join("bad.exr").display().to_string()];
            args.extend(files.iter().map(|p| p.display().to_string()));
            Command::new(env!("CARGO_BIN_EXE_worley")).args(&args).output().unwrap()
        };
        let twice = stitch(&[&tiles[0], &tiles[1], &tiles[1], &tiles[2]]);
        assert_eq!(twice.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&twice.stderr).contains("overlaps"));
        let missing = stitch(&[&tiles[0], &tiles[2]]);
        assert!(String::from_utf8_lossy(&missing.stderr).contains("pixels are in none of the files"));
        assert!(!dir.join("bad.exr").exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `worley gallery --exr` writes each figure's raw values beside its PNG:
/// the first tile of Figure 4.2 is the library's F1 at each pixel, and the
/// gaps between tiles are NaN.
#[test]
fn the_gallery_writes_its_float_maps_as_exr() {
    let dir = scratch("gallery");
    let out = worley(&["gallery", "--out", dir.to_str().unwrap(), "--tile", "16", "--exr"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let listed = String::from_utf8(out.stdout).unwrap();
    assert_eq!(listed.lines().filter(|l| l.ends_with(".exr")).count(), 8, "{listed}");
    let (display, channels, _) = read_exr(&dir.join("fig4_2_f1_f2_f3_crackle.exr"));
    assert_eq!((display.size.0, display.size.1), (34, 34));
    assert_eq!(png_size(&dir.join("fig4_2_f1_f2_f3_crackle.png")), (34, 34));
    let values = f32s(&channels[&(None, "value".to_string())].2);
    let f1 = Texture::<3, 1>::new(Config::default(), Combination::f(1), Fractal::default(), None).unwrap();
    for j in 0..16 {
        for i in 0..16 {
            let [x, y] = pixel([0.0, 0.0], 8.0, 16, i, j);
            assert_eq!(values[j * 34 + i].to_bits(), f1.value([x, y, 0.5]).to_bits(), "pixel {i}, {j}");
        }
        assert!(values[j * 34 + 16].is_nan() && values[j * 34 + 17].is_nan());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
