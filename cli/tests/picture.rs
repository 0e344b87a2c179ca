//! The picture writers: PFM round trips with its bottom-up rows, the colour
//! maps' ends and NaN marker, and a failed write leaving nothing behind.
//! (Integration tests rather than unit tests: a unit-test build of the
//! command line's library compiled all of its kernels a second time.)

use worley_cli::picture::{from_pfm, to_pfm, write_output, ColourMap};

#[test]
fn pfm_round_trips_with_rows_in_order() {
    let values: Vec<f32> = (0..12).map(|i| i as f32 * 0.5 - 1.0).chain([f32::NAN]).take(12).collect();
    let bytes = to_pfm(4, 3, &values);
    assert!(bytes.starts_with(b"Pf\n4 3\n-1.0\n"));
    // The first stored row is the bottom one.
    let first = f32::from_le_bytes(bytes[12..16].try_into().unwrap());
    assert_eq!(first, values[8]);
    let (w, h, back) = from_pfm(&bytes).unwrap();
    assert_eq!((w, h), (4, 3));
    assert_eq!(
        back.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        values.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    assert!(from_pfm(&bytes[..bytes.len() - 1]).is_err());
    assert!(from_pfm(b"PF\n1 1\n-1\n\0\0\0\0").is_err());
}

#[test]
fn colour_maps_span_their_ends_and_mark_nan() {
    for (_, m) in ColourMap::ALL {
        assert_ne!(m.colour(0.0), m.colour(1.0));
        assert_eq!(m.colour(-3.0), m.colour(0.0));
        assert_eq!(m.colour(7.0), m.colour(1.0));
        assert_eq!(m.colour(f32::NAN), [255, 0, 255]);
    }
    assert_eq!(ColourMap::Gray.colour(0.5), [128, 128, 128]);
    assert!("plasma".parse::<ColourMap>().unwrap_err().contains("gray, heat, ice, earth"));
}

#[test]
fn a_failed_write_leaves_nothing_behind() {
    let dir = std::env::temp_dir().join(format!("worley-picture-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A folder is refused before anything is written; a file in a
    // folder that does not exist fails at the temporary file.
    let target = dir.join("taken");
    std::fs::create_dir_all(target.join("inner")).unwrap();
    assert!(write_output(&target, b"data").unwrap_err().contains("it is a folder"));
    assert!(write_output(&dir.join("missing/x.bin"), b"data").unwrap_err().contains("cannot write"));
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left, vec![std::ffi::OsString::from("taken")]);
    write_output(&dir.join("ok.bin"), b"data").unwrap();
    assert_eq!(std::fs::read(dir.join("ok.bin")).unwrap(), b"data");
    std::fs::remove_dir_all(&dir).unwrap();
}
