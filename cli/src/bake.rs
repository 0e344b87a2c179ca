//! OpenEXR bakes: the channels a user asks for in one file (float values,
//! the feature ID as a 32-bit unsigned channel, compressed, the
//! configuration in the header), windows of the image for render farms,
//! stacks of planes for volume textures, and [`stitch`], which assembles
//! the windows into the whole image.
//!
//! A window's pixels are the same bits as those pixels of the whole image
//! (see [`crate::views::render_window`]), and each file records its window
//! as its data window inside the whole image's display window, so any
//! EXR tool can place it; [`stitch`] checks that the windows cover the
//! image once.

use std::collections::BTreeMap;
use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, ImageAttributes, IntegerBounds, Layer,
    LayerAttributes, SmallVec, Text, Vec2, WritableImage,
};
use worley::texture::{Combination, Texture};
use worley::{Features32, Outputs, Simd, SimdBorder};

use crate::views::{self, View, Window};

/// One quantity a bake can write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Channel {
    /// The texture: the combination, fractal sum and footprint the render
    /// shows (the PFM's values).
    Value,
    /// F1 of the basis (one octave at the texture's first frequency, point
    /// samples, the texture's period).
    F1,
    /// F2 of the basis.
    F2,
    /// F2 − F1 of the basis, as the kernel's f32 subtraction gives it.
    Crackle,
    /// The ID of F1's feature point (32-bit unsigned).
    Id,
    /// The vector from the pixel to F1's feature point, one channel per
    /// axis (`delta.X`, `delta.Y`, ...).
    Delta,
    /// The distance to the cell's border (Euclidean only).
    Border,
    /// The texture's bump normal (`normal.X/Y/Z`), with `--strength` and
    /// the footprint of `--filtered`.
    Normal,
}

impl Channel {
    /// Every channel with its command-line name.
    pub const ALL: [(&'static str, Channel); 8] = [
        ("value", Channel::Value),
        ("F1", Channel::F1),
        ("F2", Channel::F2),
        ("F2-F1", Channel::Crackle),
        ("id", Channel::Id),
        ("delta", Channel::Delta),
        ("border", Channel::Border),
        ("normal", Channel::Normal),
    ];

    /// The channels a bake writes when none are named: the value, the
    /// basis's F1, F2, F2 − F1, ID and delta, the border where the
    /// combination is the border, the normal where the shading is a bump.
    pub fn defaults(combination: &Combination, bump: bool) -> Vec<Channel> {
        let mut list = vec![Channel::Value, Channel::F1, Channel::F2, Channel::Crackle, Channel::Id, Channel::Delta];
        if matches!(combination, Combination::Border) {
            list.push(Channel::Border);
        }
        if bump {
            list.push(Channel::Normal);
        }
        list
    }
}

/// The channels of `--channels`, in the order named.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Channels(pub Vec<Channel>);

/// Parses `--channels`: names from [`Channel::ALL`], comma-separated, or
/// `all`.
pub fn parse_channels(s: &str) -> Result<Channels, String> {
    if s == "all" {
        return Ok(Channels(Channel::ALL.iter().map(|&(_, c)| c).collect()));
    }
    let mut list = Vec::new();
    for name in s.split(',').map(str::trim) {
        let Some(&(_, c)) = Channel::ALL.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)) else {
            let names: Vec<&str> = Channel::ALL.iter().map(|(n, _)| *n).collect();
            return Err(format!("unknown channel {name:?}: use all, or some of {}", names.join(",")));
        };
        if !list.contains(&c) {
            list.push(c);
        }
    }
    Ok(Channels(list))
}

/// Where a bake's pixels come from: the render's settings beside the view.
pub struct Source<'a, const D: usize, const N: usize> {
    /// The rendered texture.
    pub texture: &'a Texture<D, N>,
    /// The image, or volume, of the whole bake.
    pub view: &'a View,
    /// Whether values stand for pixel footprints.
    pub filtered: bool,
    /// Bump height per unit of value, for the normals.
    pub strength: f32,
}

/// One channel's samples over a window.
pub enum Samples {
    /// Float values.
    F32(Vec<f32>),
    /// Unsigned integers.
    U32(Vec<u32>),
}

/// The named channels of `list` over the window, in file order (names
/// sorted as EXR requires), `value` given (the render has it already).
///
/// # Errors
/// A configuration the basis or the border refuses (the border needs the
/// Euclidean metric).
pub fn channels<const D: usize, const N: usize>(
    source: &Source<'_, D, N>,
    window: &Window,
    value: Vec<f32>,
    list: &[Channel],
) -> Result<Vec<(String, Samples)>, String> {
    let (texture, view) = (source.texture, source.view);
    let mut out: Vec<(String, Samples)> = Vec::new();
    let axes = ["X", "Y", "Z", "W"];
    if list.contains(&Channel::Value) {
        out.push(("value".into(), Samples::F32(value)));
    }
    let basis = [Channel::F1, Channel::F2, Channel::Crackle, Channel::Id, Channel::Delta];
    if list.iter().any(|c| basis.contains(c)) {
        let outputs = if list.contains(&Channel::Delta) {
            Outputs::IdsAndDeltas
        } else if list.contains(&Channel::Id) {
            Outputs::Ids
        } else {
            Outputs::Distances
        };
        let config = worley::Config { order: 2, ..*texture.kernel().config() };
        let simd = Simd::<D, 2>::new(config, outputs).map_err(|e| e.to_string())?;
        let empty = simd.evaluate([0.0; D]);
        let mut f = vec![empty; window.len()];
        match texture.period() {
            None => {
                let grid = view.grid::<D>();
                let rows = |first: usize, rows: &mut [Features32<D, 2>]| {
                    simd.evaluate_grid_rows(&grid, first, rows).expect("whole rows within the grid")
                };
                views::from_rows(view, window, &mut f, empty, rows, |v| *v);
            }
            Some(period) => {
                views::by_eights(view, window, &mut f, |block| simd.evaluate8_periodic(block, &period).lanes())
            }
        }
        let column = |g: &dyn Fn(&Features32<D, 2>) -> f32| Samples::F32(f.iter().map(g).collect());
        for &c in list {
            match c {
                Channel::F1 => out.push(("F1".into(), column(&|v| v.distance[0]))),
                Channel::F2 => out.push(("F2".into(), column(&|v| v.distance[1]))),
                Channel::Crackle => out.push(("F2-F1".into(), column(&|v| v.distance[1] - v.distance[0]))),
                Channel::Id => out.push(("id".into(), Samples::U32(f.iter().map(|v| v.id[0]).collect()))),
                Channel::Delta => {
                    for (a, axis) in axes.iter().enumerate().take(D) {
                        out.push((format!("delta.{axis}"), column(&|v| v.delta[0][a])));
                    }
                }
                _ => {}
            }
        }
    }
    if list.contains(&Channel::Border) {
        let border =
            SimdBorder::<D>::new(*texture.kernel().config()).map_err(|e| format!("the border channel: {e}"))?;
        let mut d = vec![0f32; window.len()];
        views::by_eights(view, window, &mut d, |block| {
            let b = match texture.period() {
                Some(p) => border.border8_periodic(block, &p),
                None => border.border8(block),
            };
            b.distance.to_array()
        });
        out.push(("border".into(), Samples::F32(d)));
    }
    if list.contains(&Channel::Normal) {
        let footprint = views::footprint(view, source.filtered);
        let mut n = vec![[0f32; 3]; window.len()];
        views::by_eights(view, window, &mut n, |block| {
            views::normals(texture, block, footprint, source.strength).map(|v| v.to_array())
        });
        for (a, axis) in axes.iter().enumerate().take(3) {
            out.push((format!("normal.{axis}"), Samples::F32(n.iter().map(|v| v[a]).collect())));
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(out)
}

/// One plane of a bake: its name (none for a single image), its window and
/// its channels.
pub struct Plane {
    /// The layer's name (`z0003` for plane 3 of a volume).
    pub name: Option<String>,
    /// The plane's coordinate on axis 2 in 3D and 4D (the header's
    /// `worley.z`).
    pub z: Option<f64>,
    /// The pixels baked.
    pub window: Window,
    /// Channels in file order.
    pub channels: Vec<(String, Samples)>,
}

/// The EXR file of a bake: one layer per plane, each with its window as the
/// data window inside the whole image (`width` × `height`), compressed
/// losslessly (ZIP). Each layer's header holds the software's name and one
/// text attribute `worley`: `settings` as `key=value` pairs joined by `; `,
/// then the plane's `z`. One attribute, so that the same bake gives the
/// same bytes (the encoder writes its custom attributes in a hash map's
/// order, which changes from run to run).
///
/// # Errors
/// The EXR encoder's error.
pub fn encode(width: usize, height: usize, planes: Vec<Plane>, settings: &[(&str, String)]) -> Result<Vec<u8>, String> {
    let mut layers = Vec::new();
    for plane in planes {
        let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = plane
            .channels
            .into_iter()
            .map(|(name, samples)| {
                let data = match samples {
                    Samples::F32(v) => FlatSamples::F32(v),
                    Samples::U32(v) => FlatSamples::U32(v),
                };
                AnyChannel::new(name.as_str(), data)
            })
            .collect();
        let mut attributes = match &plane.name {
            Some(name) => LayerAttributes::named(name.as_str()),
            None => LayerAttributes::default(),
        };
        attributes.layer_position = Vec2(plane.window.x as i32, plane.window.y as i32);
        attributes.software_name = Some(Text::from(concat!("worley ", env!("CARGO_PKG_VERSION"))));
        let mut pairs: Vec<String> = settings.iter().map(|(k, v)| format!("{k}={v}")).collect();
        if let Some(z) = plane.z {
            pairs.push(format!("z={z}"));
        }
        attributes.other.insert(Text::from("worley"), AttributeValue::Text(Text::from(pairs.join("; ").as_str())));
        let size = Vec2(plane.window.width, plane.window.height);
        layers.push(Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, AnyChannels::sort(list)));
    }
    let display = IntegerBounds::new(Vec2(0, 0), Vec2(width, height));
    let image = Image::from_layers(ImageAttributes::new(display), layers);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).map_err(|e| format!("cannot encode the EXR: {e}"))?;
    Ok(bytes.into_inner())
}

/// The windows of `--region` or `--tile` in one plane: the band I of N
/// takes rows ⌊I·H/N⌋..⌊(I+1)·H/N⌋ of all columns.
///
/// # Errors
/// A band index not below the count, more bands than rows.
pub fn band(view: &View, index: usize, count: usize) -> Result<Window, String> {
    if count == 0 || index >= count || count > view.height {
        return Err(format!(
            "tile {index}/{count}: use I/N with 0 <= I < N and N at most the image's height ({})",
            view.height
        ));
    }
    let (y0, y1) = (index * view.height / count, (index + 1) * view.height / count);
    Ok(Window { x: 0, y: y0, width: view.width, height: y1 - y0, plane: 0 })
}

/// `worley stitch`: reads the EXR files of a bake's windows and writes the
/// whole image, layer by layer (planes of a volume stay apart), with the
/// first file's attributes. Every window's channels must be the same and
/// every pixel of the display window covered once.
///
/// # Errors
/// A file that cannot be read, windows that disagree, overlap, or leave
/// pixels uncovered.
pub fn stitch(inputs: &[impl AsRef<Path>], output: &Path) -> Result<String, String> {
    use exr::prelude::ReadChannels as _;
    use exr::prelude::ReadLayers as _;
    struct Whole {
        bounds: IntegerBounds,
        attributes: LayerAttributes,
        encoding: Encoding,
        channels: Vec<(Text, FlatSamples)>,
        covered: Vec<bool>,
    }
    let mut wholes: BTreeMap<Option<Text>, Whole> = BTreeMap::new();
    let mut display: Option<IntegerBounds> = None;
    for input in inputs {
        let input = input.as_ref();
        let image = exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .from_file(input)
            .map_err(|e| format!("cannot read {}: {e}", input.display()))?;
        let bounds = image.attributes.display_window;
        if *display.get_or_insert(bounds) != bounds {
            return Err(format!("{}: its whole image differs from the first file's", input.display()));
        }
        for layer in image.layer_data {
            let name = layer.attributes.layer_name.clone();
            let names: Vec<&Text> = layer.channel_data.list.iter().map(|c| &c.name).collect();
            let whole = wholes.entry(name.clone()).or_insert_with(|| {
                let n = bounds.size.area();
                Whole {
                    bounds,
                    attributes: layer.attributes.clone(),
                    encoding: layer.encoding,
                    channels: layer
                        .channel_data
                        .list
                        .iter()
                        .map(|c| {
                            let empty = match c.sample_data {
                                FlatSamples::U32(_) => FlatSamples::U32(vec![0; n]),
                                FlatSamples::F16(_) => FlatSamples::F16(vec![Default::default(); n]),
                                FlatSamples::F32(_) => FlatSamples::F32(vec![f32::NAN; n]),
                            };
                            (c.name.clone(), empty)
                        })
                        .collect(),
                    covered: vec![false; n],
                }
            });
            let same = whole.channels.len() == names.len()
                && whole.channels.iter().zip(&names).all(|((a, _), b)| a == *b)
                && whole
                    .channels
                    .iter()
                    .zip(&layer.channel_data.list)
                    .all(|((_, a), b)| std::mem::discriminant(a) == std::mem::discriminant(&b.sample_data));
            if !same {
                return Err(format!("{}: its channels differ from the first file's", input.display()));
            }
            let (pos, size) = (layer.attributes.layer_position, layer.size);
            let (x0, y0) = (pos.0 - bounds.position.0, pos.1 - bounds.position.1);
            let inside =
                x0 >= 0 && y0 >= 0 && x0 as usize + size.0 <= bounds.size.0 && y0 as usize + size.1 <= bounds.size.1;
            if !inside {
                return Err(format!("{}: its window lies outside the whole image", input.display()));
            }
            let w = bounds.size.0;
            for y in 0..size.1 {
                let row = (y0 as usize + y) * w + x0 as usize;
                if whole.covered[row..row + size.0].iter().any(|&c| c) {
                    return Err(format!("{}: its window overlaps another file's", input.display()));
                }
                whole.covered[row..row + size.0].fill(true);
            }
            for ((_, dst), src) in whole.channels.iter_mut().zip(&layer.channel_data.list) {
                for y in 0..size.1 {
                    let (row, from) = ((y0 as usize + y) * w + x0 as usize, y * size.0);
                    match (&mut *dst, &src.sample_data) {
                        (FlatSamples::F32(d), FlatSamples::F32(s)) => {
                            d[row..row + size.0].copy_from_slice(&s[from..from + size.0])
                        }
                        (FlatSamples::U32(d), FlatSamples::U32(s)) => {
                            d[row..row + size.0].copy_from_slice(&s[from..from + size.0])
                        }
                        (FlatSamples::F16(d), FlatSamples::F16(s)) => {
                            d[row..row + size.0].copy_from_slice(&s[from..from + size.0])
                        }
                        _ => unreachable!("the sample types were compared above"),
                    }
                }
            }
        }
    }
    let Some(display) = display else {
        return Err("no input files".into());
    };
    let mut layers = Vec::new();
    let mut summary = Vec::new();
    for (name, whole) in wholes {
        let missing = whole.covered.iter().filter(|&&c| !c).count();
        let label = name.as_ref().map_or("the image".to_string(), |n| format!("layer {n}"));
        if missing > 0 {
            return Err(format!("{label}: {missing} pixels are in none of the files"));
        }
        summary.push(label);
        let mut attributes = whole.attributes;
        attributes.layer_position = whole.bounds.position;
        let list: SmallVec<[AnyChannel<FlatSamples>; 4]> =
            whole.channels.into_iter().map(|(name, data)| AnyChannel::new(name, data)).collect();
        layers.push(Layer::new(whole.bounds.size, attributes, whole.encoding, AnyChannels::sort(list)));
    }
    let image = Image::from_layers(ImageAttributes::new(display), layers);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).map_err(|e| format!("cannot encode the EXR: {e}"))?;
    crate::picture::write_output(output, &bytes.into_inner())?;
    Ok(format!(
        "stitched {} files into {} ({}x{}, {})",
        inputs.len(),
        output.display(),
        display.size.0,
        display.size.1,
        summary.join(", ")
    ))
}
