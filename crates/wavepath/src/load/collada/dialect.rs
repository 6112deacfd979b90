//! Whether a COLLADA file is one of the CS184 course's scenes, whose effects keep the
//! course's reading (the CGL extras, else diffuse with the common profile's diffuse colour),
//! or a file from another tool, whose common profile is read in full (`common.rs`).
//!
//! The course's files (COLLADA-CS184.md in the shared scenes) either carry the course's
//! extensions (a `<technique profile="CGL">` or `"CMU462"` anywhere) or were all exported by
//! Blender 2.72 or 2.74 (`<authoring_tool>`; some, such as `keenan/banana.dae`, have no
//! extension and Phong effects whose specular colour the course renderer never showed).

use super::xml::{CS184_PROFILES, child, path};
use roxmltree::Node;

/// Blender versions that exported the course's scenes.
const COURSE_EXPORTERS: [&str; 2] = ["Blender 2.72", "Blender 2.74"];

pub fn is_course_file(root: Node) -> bool {
    let extension = root.descendants().any(|n| {
        n.is_element()
            && n.tag_name().name() == "technique"
            && n.attribute("profile").is_some_and(|p| CS184_PROFILES.contains(&p))
    });
    let tool = child(root, "asset")
        .and_then(|a| path(a, &["contributor", "authoring_tool"]))
        .and_then(|t| t.text())
        .is_some_and(|t| COURSE_EXPORTERS.iter().any(|e| t.trim_start().starts_with(e)));
    extension || tool
}
