//! Step 1, parsing: the XML document, line numbers, and reading numbers, vectors and
//! origins out of elements with errors that name the file, line and element.
//!
//! roxmltree is used (rather than a serde mapping) because every error must name the
//! file, the line and the element: roxmltree keeps node positions. Its own
//! `text_pos_at` scans the text from the start on every call, which made loading
//! quadratic in the file's size; [`LineIndex`] answers in `O(log n)`.

use nalgebra::Vector3;
use roxmltree::{Document, Node};

use crate::error::UrdfError;
use crate::spatial::{rpy_to_matrix, Transform};

/// Byte offsets of the line starts of a text, for 1-based line numbers by binary search.
pub(super) struct LineIndex {
    starts: Vec<usize>,
}

impl LineIndex {
    pub(super) fn new(text: &str) -> Self {
        let mut starts = vec![0];
        starts.extend(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        Self { starts }
    }

    /// 1-based line of byte offset `pos`.
    pub(super) fn line(&self, pos: usize) -> u32 {
        let row = self.starts.partition_point(|&start| start <= pos);
        u32::try_from(row).unwrap_or(u32::MAX)
    }
}

/// The parsed document and where it came from: everything an error message needs.
pub(super) struct Ctx<'a, 'i> {
    pub(super) file: &'a str,
    pub(super) doc: &'a Document<'i>,
    lines: LineIndex,
}

impl<'a, 'i> Ctx<'a, 'i> {
    pub(super) fn new(file: &'a str, doc: &'a Document<'i>, text: &str) -> Self {
        Self {
            file,
            doc,
            lines: LineIndex::new(text),
        }
    }

    /// 1-based line where `node` starts.
    pub(super) fn line(&self, node: Node) -> u32 {
        self.lines.line(node.range().start)
    }

    /// An error about `element` (at `node`'s line when given).
    pub(super) fn err(
        &self,
        node: Option<Node>,
        element: impl Into<String>,
        problem: impl Into<String>,
    ) -> UrdfError {
        UrdfError {
            file: self.file.to_string(),
            line: node.map(|n| self.line(n)),
            element: element.into(),
            problem: problem.into(),
        }
    }

    /// The finite number in attribute `attr`, if present.
    pub(super) fn number(
        &self,
        node: Node,
        element: &str,
        attr: &str,
    ) -> Result<Option<f64>, UrdfError> {
        let Some(text) = node.attribute(attr) else {
            return Ok(None);
        };
        parse_finite(text.trim())
            .map(Some)
            .map_err(|p| self.err(Some(node), format!("{element} attribute '{attr}'"), p))
    }

    /// The finite number in attribute `attr`, which must be present.
    pub(super) fn required_number(
        &self,
        node: Node,
        element: &str,
        attr: &str,
    ) -> Result<f64, UrdfError> {
        self.number(node, element, attr)?
            .ok_or_else(|| self.err(Some(node), element, format!("missing attribute '{attr}'")))
    }

    /// Three finite numbers in attribute `attr`, if present.
    pub(super) fn vector3(
        &self,
        node: Node,
        element: &str,
        attr: &str,
    ) -> Result<Option<Vector3<f64>>, UrdfError> {
        let Some(text) = node.attribute(attr) else {
            return Ok(None);
        };
        let bad = |problem: String| {
            self.err(Some(node), format!("{element} attribute '{attr}'"), problem)
        };
        let mut v = Vector3::zeros();
        let mut count = 0;
        for part in text.split_whitespace() {
            if count < 3 {
                v[count] = parse_finite(part).map_err(&bad)?;
            }
            count += 1;
        }
        if count != 3 {
            return Err(bad(format!("expected 3 numbers, found {text:?}")));
        }
        Ok(Some(v))
    }

    /// The `<origin xyz rpy>` child of `parent` (identity when absent).
    pub(super) fn origin(&self, parent: Node, element: &str) -> Result<Transform, UrdfError> {
        let Some(origin) = child(parent, "origin") else {
            return Ok(Transform::identity());
        };
        let el = format!("{element} <origin>");
        let xyz = self
            .vector3(origin, &el, "xyz")?
            .unwrap_or_else(Vector3::zeros);
        let rpy = self
            .vector3(origin, &el, "rpy")?
            .unwrap_or_else(Vector3::zeros);
        Ok(Transform::new(rpy_to_matrix(rpy.x, rpy.y, rpy.z), xyz))
    }
}

/// A finite number, or a message saying why `text` is not one.
pub(super) fn parse_finite(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("'{text}' is not a finite number")),
        Err(_) => Err(format!("'{text}' is not a number")),
    }
}

/// The first child element of `node` called `tag`.
pub(super) fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

/// Parses `text` as XML; `source` names it in the error.
pub(super) fn parse_document<'i>(text: &'i str, source: &str) -> Result<Document<'i>, UrdfError> {
    Document::parse(text).map_err(|e| UrdfError {
        file: source.to_string(),
        line: Some(e.pos().row),
        element: "XML".into(),
        problem: format!("not well-formed XML: {e}"),
    })
}

/// Decodes a file's bytes as UTF-8, or says where the first byte that is not UTF-8 is.
pub(super) fn utf8_text(bytes: Vec<u8>, source: &str) -> Result<String, UrdfError> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let valid = std::str::from_utf8(&e.as_bytes()[..at]).unwrap_or("");
        UrdfError {
            file: source.to_string(),
            line: Some(LineIndex::new(valid).line(at)),
            element: "file".into(),
            problem: format!(
                "not UTF-8 text (byte {at} is 0x{:02x}): save the URDF as UTF-8",
                e.as_bytes()[at]
            ),
        }
    })
}
