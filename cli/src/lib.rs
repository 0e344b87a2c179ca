//! The `worley` command's parts, as a library so that its tests and the
//! repository's examples can use them: the subcommands, the picture writers
//! and the views that shade textures into images.
#![deny(missing_docs)]

pub mod commands;
pub mod picture;
pub mod render_cmd;
pub mod tune;
pub mod views;
