//! The shape of URDF text, checked before it is parsed: the URDF parser (`urdf-rs` over
//! `serde-xml-rs`) recurses once per nested element, so 20,000 nested elements (a 140 KB
//! file) overflow the stack, and its work grows faster than the file. One pass of a
//! non-recursive XML parser (roxmltree, without DTDs so without entity expansion, and with
//! at most [`MAX_URDF_NODES`] nodes) measures the nesting depth iteratively and refuses more
//! than [`MAX_URDF_DEPTH`] levels. Errors give positions and limits, never the file's text.

use roxmltree::{Document, ParsingOptions};

/// The deepest nesting of elements in a URDF (real files nest 6 levels:
/// robot/link/visual/geometry/mesh; extensions such as `<gazebo>` a few more).
pub const MAX_URDF_DEPTH: usize = 64;

/// The most XML nodes (elements, text including whitespace, comments) in a URDF: a 100-link
/// robot with visuals, collisions and inertias has about 10,000.
pub const MAX_URDF_NODES: u32 = 200_000;

/// Checks that `urdf` is XML of at most [`MAX_URDF_NODES`] nodes nested at most
/// [`MAX_URDF_DEPTH`] deep; the reason otherwise (positions and limits only).
pub(super) fn check_urdf_shape(urdf: &str) -> std::result::Result<(), String> {
    let options = ParsingOptions { allow_dtd: false, nodes_limit: MAX_URDF_NODES, ..Default::default() };
    let doc = Document::parse_with_options(urdf, options).map_err(|e| match e {
        roxmltree::Error::NodesLimitReached => {
            format!("more than {MAX_URDF_NODES} XML nodes (the limit of a URDF's elements, text and comments)")
        }
        e => {
            let at = e.pos();
            format!("not well-formed XML at line {}, column {}", at.row, at.col)
        }
    })?;
    // Nodes come in document order, each after its parent: one pass gives every depth.
    let mut depths = vec![0usize; doc.descendants().count()];
    for node in doc.descendants() {
        let depth = match node.parent() {
            Some(parent) => depths.get(parent.id().get_usize()).copied().unwrap_or(0) + usize::from(node.is_element()),
            None => 0,
        };
        if depth > MAX_URDF_DEPTH {
            let at = doc.text_pos_at(node.range().start);
            return Err(format!(
                "elements nested more than {MAX_URDF_DEPTH} deep (the limit of a URDF's nesting), at line {}, column {}",
                at.row, at.col
            ));
        }
        if let Some(slot) = depths.get_mut(node.id().get_usize()) {
            *slot = depth;
        }
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    fn nested(levels: usize) -> String {
        format!("<robot name=\"r\">{}{}</robot>", "<x>".repeat(levels), "</x>".repeat(levels))
    }

    #[test]
    fn depth_at_the_limit_passes_and_one_more_is_refused() {
        assert!(check_urdf_shape(&nested(MAX_URDF_DEPTH - 1)).is_ok());
        let err = check_urdf_shape(&nested(MAX_URDF_DEPTH)).unwrap_err();
        assert!(err.contains("nested more than 64 deep"), "{err}");
    }

    #[test]
    fn node_count_is_bounded() {
        let flat = format!("<robot name=\"r\">{}</robot>", "<x/>".repeat(MAX_URDF_NODES as usize));
        assert!(check_urdf_shape(&flat).unwrap_err().contains("more than 200000 XML nodes"));
    }

    #[test]
    fn malformed_text_is_not_quoted() {
        let err = check_urdf_shape("<robot><SECRET></robot>").unwrap_err();
        assert!(err.starts_with("not well-formed XML at line 1") && !err.contains("SECRET"), "{err}");
    }
}
