//! Reading the XML tree: id look-up, element paths in error messages, and number lists.
//!
//! Every error goes through [`Doc::err`], so each one names the file, the line and the
//! element, and stays on one line.

use anyhow::{Error, Result, anyhow};
use roxmltree::{Document, Node};
use std::collections::HashMap;
use std::fmt::Display;

/// Profiles whose `<technique>` carries the CS184 extensions (2015 files write CMU462).
pub const CS184_PROFILES: [&str; 2] = ["CGL", "CMU462"];

/// The parsed document with an index of its `id` attributes.
pub struct Doc<'a, 'input> {
    pub file: &'a str,
    pub doc: &'a Document<'input>,
    ids: HashMap<&'a str, Node<'a, 'input>>,
}

impl<'a, 'input> Doc<'a, 'input> {
    pub fn new(file: &'a str, doc: &'a Document<'input>) -> Self {
        let mut ids = HashMap::new();
        for n in doc.descendants().filter(|n| n.is_element()) {
            if let Some(id) = n.attribute("id") {
                // The first element with an id wins, as in a browser.
                ids.entry(id).or_insert(n);
            }
        }
        Doc { file, doc, ids }
    }

    /// The element whose `id` is `id`.
    pub fn by_id(&self, id: &str) -> Option<Node<'a, 'input>> {
        self.ids.get(id).copied()
    }

    /// One-line error naming the file, the element (with its line) and the problem.
    pub fn err(&self, node: Node, msg: impl Display) -> Error {
        let pos = self.doc.text_pos_at(node.range().start);
        let id = node.attribute("id").map(|i| format!(" id=\"{}\"", clip(i))).unwrap_or_default();
        anyhow!("{}: line {}: <{}{}>: {}", self.file, pos.row, node.tag_name().name(), id, msg)
    }

    /// Resolves a URL attribute (`#id`) of `node`, checking the target's element name.
    pub fn resolve(&self, node: Node<'a, 'input>, attr: &str, expect: &[&str]) -> Result<Node<'a, 'input>> {
        let url = node.attribute(attr).ok_or_else(|| self.err(node, format!("missing '{attr}' attribute")))?;
        let id = url
            .strip_prefix('#')
            .ok_or_else(|| self.err(node, format!("{attr}=\"{}\" is not a local reference '#id'", clip(url))))?;
        let target = *self
            .ids
            .get(id)
            .ok_or_else(|| self.err(node, format!("{attr}=\"{}\" refers to an id that does not exist", clip(url))))?;
        if !expect.contains(&target.tag_name().name()) {
            return Err(self.err(
                node,
                format!(
                    "{attr}=\"{}\" refers to a <{}>, expected <{}>",
                    clip(url),
                    target.tag_name().name(),
                    expect.join("> or <")
                ),
            ));
        }
        Ok(target)
    }

    /// Parses whitespace-separated floats; NaN and infinities are errors.
    /// `at_most` bounds the number read (the declared count); `None` reads everything.
    pub fn floats(&self, node: Node, at_most: Option<usize>) -> Result<Vec<f32>> {
        let text = node_text(node);
        let cap = at_most.unwrap_or(usize::MAX).min(text.len() / 2 + 1);
        let mut out = Vec::with_capacity(cap);
        for tok in text.split_ascii_whitespace() {
            if Some(out.len()) == at_most {
                break;
            }
            let v: f32 = tok.parse().map_err(|_| self.err(node, format!("'{}' is not a number", clip(tok))))?;
            if !v.is_finite() {
                return Err(self.err(node, format!("'{}' is not a finite number", clip(tok))));
            }
            out.push(v);
        }
        Ok(out)
    }

    /// Parses whitespace-separated non-negative integers (index lists, vertex counts).
    pub fn uints(&self, node: Node) -> Result<Vec<u32>> {
        let text = node_text(node);
        let mut out = Vec::with_capacity(text.len() / 2 + 1);
        for tok in text.split_ascii_whitespace() {
            let v: u32 =
                tok.parse().map_err(|_| self.err(node, format!("'{}' is not a non-negative integer", clip(tok))))?;
            out.push(v);
        }
        Ok(out)
    }

    /// Exactly `N` floats from the element's text.
    pub fn floats_n<const N: usize>(&self, node: Node) -> Result<[f32; N]> {
        let v = self.floats(node, None)?;
        v.try_into().map_err(|v: Vec<f32>| self.err(node, format!("expected {N} numbers, found {}", v.len())))
    }

    /// An RGB colour: 3 or 4 numbers (alpha ignored).
    pub fn color(&self, node: Node) -> Result<glam::Vec3> {
        let v = self.floats(node, Some(4))?;
        if v.len() < 3 {
            return Err(self.err(node, format!("a colour needs 3 numbers, found {}", v.len())));
        }
        Ok(glam::Vec3::new(v[0], v[1], v[2]))
    }

    /// One float.
    pub fn float(&self, node: Node) -> Result<f32> {
        Ok(self.floats_n::<1>(node)?[0])
    }

    /// A non-negative integer attribute, if present.
    pub fn uint_attr(&self, node: Node, name: &str) -> Result<Option<usize>> {
        match node.attribute(name) {
            None => Ok(None),
            Some(s) => s
                .trim()
                .parse::<u32>()
                .map(|v| Some(v as usize))
                .map_err(|_| self.err(node, format!("{name}=\"{}\" is not a non-negative integer", clip(s)))),
        }
    }

    /// The required child element `tag`.
    pub fn child(&self, node: Node<'a, 'input>, tag: &str) -> Result<Node<'a, 'input>> {
        child(node, tag).ok_or_else(|| self.err(node, format!("missing <{tag}>")))
    }
}

/// The first child element with this local name.
pub fn child<'a, 'input>(node: Node<'a, 'input>, tag: &str) -> Option<Node<'a, 'input>> {
    node.children().find(|c| c.is_element() && c.tag_name().name() == tag)
}

/// All child elements with this local name, in document order.
pub fn children<'a, 'input: 'a>(node: Node<'a, 'input>, tag: &'a str) -> impl Iterator<Item = Node<'a, 'input>> + 'a {
    node.children().filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

/// Follows a path of child element names.
pub fn path<'a, 'input>(node: Node<'a, 'input>, tags: &[&str]) -> Option<Node<'a, 'input>> {
    tags.iter().try_fold(node, |n, t| child(n, t))
}

/// The first element child of the CS184 technique (`<extra><technique profile="CGL">`) of `node`.
pub fn cs184_extra<'a, 'input>(node: Node<'a, 'input>) -> Option<Node<'a, 'input>> {
    children(node, "extra")
        .flat_map(|e| children(e, "technique"))
        .find(|t| t.attribute("profile").is_some_and(|p| CS184_PROFILES.contains(&p)))
        .and_then(|t| t.children().find(|c| c.is_element()))
}

/// The element's text; a borrowed slice of the file unless it holds entities or comments.
fn node_text<'a>(node: Node<'a, '_>) -> std::borrow::Cow<'a, str> {
    let mut texts = node.children().filter(|c| c.is_text()).filter_map(|c| c.text());
    match (texts.next(), texts.next()) {
        (None, _) => "".into(),
        (Some(a), None) => a.into(),
        (Some(a), Some(b)) => {
            // Text split by a comment: join the pieces with a separator.
            let mut s = format!("{a} {b}");
            for t in texts {
                s.push(' ');
                s.push_str(t);
            }
            s.into()
        }
    }
}

/// Keeps quoted file text short so error messages stay on one line.
pub fn clip(s: &str) -> String {
    let one_line: String = s.chars().take(40).map(|c| if c.is_control() { ' ' } else { c }).collect();
    if s.chars().count() > 40 { format!("{one_line}...") } else { one_line }
}
