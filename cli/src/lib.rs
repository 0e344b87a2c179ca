//! The `worley` command's parts, as a library so that its tests and the
//! repository's examples can use them: the subcommands, the picture writers
//! the views that shade textures into images, the EXR bakes, the gallery,
//! and the harness runs of `check` and the main job.
#![deny(missing_docs)]

pub mod bake;
pub mod commands;
pub mod gallery;
pub mod picture;
pub mod render_cmd;
pub mod runs;
pub mod tune;
pub mod views;
