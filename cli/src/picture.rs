//! Images: colour maps, PNG for looking at, PFM for renderers (the raw f32
//! values), and writes that never leave a partial file behind and go where
//! the user pointed ([`write_output`]).

use std::io::Write;
use std::path::Path;

/// A colour map from [0, 1] to 8-bit sRGB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColourMap {
    /// Black to white.
    Gray,
    /// Black, deep red, orange, yellow, white.
    Heat,
    /// Black, navy, teal, pale cyan, white.
    Ice,
    /// Dark brown, ochre, sand, cream: the chapter's stone and skin tones.
    Earth,
}

impl ColourMap {
    /// Every map, with its command-line name.
    pub const ALL: [(&'static str, ColourMap); 4] =
        [("gray", ColourMap::Gray), ("heat", ColourMap::Heat), ("ice", ColourMap::Ice), ("earth", ColourMap::Earth)];

    fn stops(self) -> &'static [[f32; 3]] {
        match self {
            ColourMap::Gray => &[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]],
            ColourMap::Heat => {
                &[[0.0, 0.0, 0.0], [0.55, 0.05, 0.02], [0.95, 0.45, 0.05], [1.0, 0.9, 0.3], [1.0, 1.0, 1.0]]
            }
            ColourMap::Ice => {
                &[[0.0, 0.0, 0.02], [0.05, 0.1, 0.4], [0.1, 0.5, 0.6], [0.7, 0.95, 0.95], [1.0, 1.0, 1.0]]
            }
            ColourMap::Earth => &[[0.12, 0.07, 0.03], [0.45, 0.3, 0.12], [0.78, 0.62, 0.38], [0.96, 0.92, 0.8]],
        }
    }

    /// The colour of `t` (clamped to [0, 1]; NaN is magenta, so bad values
    /// are never mistaken for texture).
    pub fn colour(self, t: f32) -> [u8; 3] {
        if t.is_nan() {
            return [255, 0, 255];
        }
        let stops = self.stops();
        let x = t.clamp(0.0, 1.0) * (stops.len() - 1) as f32;
        let i = (x as usize).min(stops.len() - 2);
        let w = x - i as f32;
        std::array::from_fn(|c| to_byte(stops[i][c] + w * (stops[i + 1][c] - stops[i][c])))
    }
}

impl std::str::FromStr for ColourMap {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        ColourMap::ALL.iter().find(|(n, _)| *n == s).map(|(_, m)| *m).ok_or_else(|| {
            let names: Vec<&str> = ColourMap::ALL.iter().map(|(n, _)| *n).collect();
            format!("unknown colour map {s:?}: use one of {}", names.join(", "))
        })
    }
}

/// A linear value in [0, 1] as an 8-bit byte.
pub fn to_byte(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// A distinct, stable colour for a feature ID (for flagstones): hue and
/// lightness from the ID's bits, muted like stone.
pub fn id_colour(id: u32) -> [f32; 3] {
    let mut h = id.wrapping_mul(0x9E37_79B1);
    h ^= h >> 15;
    let hue = (h & 0xFFFF) as f32 / 65536.0;
    let light = 0.45 + 0.35 * ((h >> 16) & 0xFF) as f32 / 255.0;
    let base = [
        0.5 + 0.5 * (std::f32::consts::TAU * hue).cos(),
        0.5 + 0.5 * (std::f32::consts::TAU * (hue + 1.0 / 3.0)).cos(),
        0.5 + 0.5 * (std::f32::consts::TAU * (hue + 2.0 / 3.0)).cos(),
    ];
    base.map(|c| light * (0.72 + 0.28 * c))
}

/// An 8-bit RGB image.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major pixels, top row first.
    pub pixels: Vec<[u8; 3]>,
}

impl Rgb {
    /// The PNG encoding.
    ///
    /// # Errors
    /// The encoder's message (e.g. a zero or oversized dimension).
    pub fn to_png(&self) -> Result<Vec<u8>, String> {
        let mut bytes = Vec::new();
        let w = u32::try_from(self.width).map_err(|e| e.to_string())?;
        let h = u32::try_from(self.height).map_err(|e| e.to_string())?;
        let mut encoder = png::Encoder::new(&mut bytes, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(self.pixels.as_flattened()).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())?;
        Ok(bytes)
    }
}

/// A greyscale PFM ("Pf", little-endian, rows bottom to top as the format
/// says) of `values` given row-major with the top row first.
pub fn to_pfm(width: usize, height: usize, values: &[f32]) -> Vec<u8> {
    assert_eq!(values.len(), width * height, "PFM of {width}x{height} needs that many values");
    let mut out = format!("Pf\n{width} {height}\n-1.0\n").into_bytes();
    for row in values.chunks(width.max(1)).rev() {
        for v in row {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Reads a greyscale PFM (either byte order) into (width, height, values
/// with the top row first).
///
/// # Errors
/// What is wrong with the file.
pub fn from_pfm(bytes: &[u8]) -> Result<(usize, usize, Vec<f32>), String> {
    let mut fields = Vec::new();
    let mut at = 0;
    while fields.len() < 4 {
        while at < bytes.len() && bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        let start = at;
        while at < bytes.len() && !bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        if start == at {
            return Err("PFM header is truncated".into());
        }
        fields.push(std::str::from_utf8(&bytes[start..at]).map_err(|e| e.to_string())?.to_string());
    }
    at += 1; // the single whitespace byte after the scale
    if fields[0] != "Pf" {
        return Err(format!("not a greyscale PFM (magic {:?})", fields[0]));
    }
    let parse = |s: &str| s.parse::<usize>().map_err(|e| format!("PFM size {s:?}: {e}"));
    let (w, h) = (parse(&fields[1])?, parse(&fields[2])?);
    let scale: f32 = fields[3].parse().map_err(|e| format!("PFM scale {:?}: {e}", fields[3]))?;
    let data = bytes.get(at..).unwrap_or(&[]);
    if data.len() != w * h * 4 {
        return Err(format!("PFM of {w}x{h} needs {} data bytes, has {}", w * h * 4, data.len()));
    }
    let values: Vec<f32> = data
        .chunks_exact(4)
        .map(|b| {
            let b = [b[0], b[1], b[2], b[3]];
            if scale < 0.0 {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
        })
        .collect();
    let mut top_first = Vec::with_capacity(values.len());
    for row in values.chunks(w.max(1)).rev() {
        top_first.extend_from_slice(row);
    }
    Ok((w, h, top_first))
}

/// Writes `bytes` where a user who typed `path` expects them:
///
/// - `-` is standard output;
/// - a symbolic link is followed (through chains of links, relative targets
///   resolved against the link's folder), so the link stays a link and its
///   target gets the bytes;
/// - a path that exists and is not a regular file (a FIFO, a device, a
///   socket) is opened and written directly, and its errors are reported
///   (`/dev/full` fails with "No space left on device");
/// - anything else (a regular file, or a new name) gets a temporary file in
///   the same folder, renamed over it, so that a failure leaves no partial
///   file and readers never see half an image.
///
/// # Errors
/// A message naming the path and the cause.
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let fail = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    if path.as_os_str() == "-" {
        let mut out = std::io::stdout().lock();
        return out
            .write_all(bytes)
            .and_then(|()| out.flush())
            .map_err(|e| format!("cannot write to standard output: {e}"));
    }
    let target = follow_links(path).map_err(fail)?;
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => Err(format!("cannot write {}: it is a folder", path.display())),
        Ok(m) if !m.is_file() => {
            let mut f = std::fs::OpenOptions::new().write(true).open(&target).map_err(fail)?;
            f.write_all(bytes).and_then(|()| f.flush()).map_err(fail)
        }
        _ => replace_file(&target, bytes).map_err(fail),
    }
}

/// The path a chain of symbolic links ends at (the path itself if it is not
/// a link, or if it does not exist).
fn follow_links(path: &Path) -> std::io::Result<std::path::PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&p)?;
                p = match p.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            _ => return Ok(p),
        }
    }
    Err(std::io::Error::other("too many levels of symbolic links"))
}

/// A temporary file beside `path`, renamed over it.
fn replace_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let name = path.file_name().ok_or_else(|| std::io::Error::other("not a file name"))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = std::fs::File::create(&tmp)
        .and_then(|mut f| f.write_all(bytes).and_then(|()| f.sync_all()))
        .and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Tiles of equal size into one sheet, `columns` across, `gap` white
/// pixels apart (NaN in the values).
pub fn sheet(tiles: &[(Vec<f32>, Rgb)], columns: usize, gap: usize) -> (Vec<f32>, Rgb) {
    let (w, h) = (tiles[0].1.width, tiles[0].1.height);
    let rows = tiles.len().div_ceil(columns);
    let (sw, sh) = (columns * w + (columns - 1) * gap, rows * h + (rows - 1) * gap);
    let mut pixels = vec![[255u8; 3]; sw * sh];
    let mut values = vec![f32::NAN; sw * sh];
    for (t, (v, img)) in tiles.iter().enumerate() {
        let (x0, y0) = ((t % columns) * (w + gap), (t / columns) * (h + gap));
        for y in 0..h {
            let dst = (y0 + y) * sw + x0;
            pixels[dst..dst + w].copy_from_slice(&img.pixels[y * w..(y + 1) * w]);
            values[dst..dst + w].copy_from_slice(&v[y * w..(y + 1) * w]);
        }
    }
    (values, Rgb { width: sw, height: sh, pixels })
}
