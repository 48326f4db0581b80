//! The ASCII `.msh` text (formats 4.1 and 2.2) read into its raw content: physical names,
//! entities (4.1), nodes and elements as the file states them (gmsh tags, 1-based line
//! numbers for messages); no mesh requirement is checked here but the format's own.

use std::collections::HashMap;

use super::error::{invalid, malformed, snippet, unsupported, GmshError, Result};

#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Version {
    V22,
    V41,
}

#[derive(Debug)]
pub(super) struct RawNode {
    pub(super) tag: i64,
    pub(super) xy: [f64; 2],
}

#[derive(Debug)]
pub(super) struct RawElement {
    pub(super) line: usize,
    pub(super) tag: i64,
    pub(super) etype: i64,
    pub(super) dim: u8,
    pub(super) physicals: Vec<i64>,
    pub(super) nodes: Vec<i64>,
}

#[derive(Debug, Default)]
pub(super) struct RawMesh {
    /// (dimension, physical tag) → name.
    pub(super) names: HashMap<(u8, i64), String>,
    pub(super) nodes: Vec<RawNode>,
    pub(super) elements: Vec<RawElement>,
}

pub(super) type Line<'a> = (usize, &'a str);

pub(super) struct Section<'a> {
    name: &'a str,
    start: usize,
    end: usize,
    body: Vec<Line<'a>>,
}

pub(super) fn parse_msh(text: &str, origin: &str) -> Result<RawMesh> {
    let version = mesh_format(text, origin)?;
    let sections = split_sections(text, origin)?;
    let once = |name: &str| -> Result<Option<&Section>> {
        let mut found = sections.iter().filter(|s| s.name == name);
        let first = found.next();
        match found.next() {
            Some(second) => Err(malformed(
                origin,
                name,
                second.start,
                "the section appears twice",
            )),
            None => Ok(first),
        }
    };
    if let Some(s) = once("PartitionedEntities")? {
        return Err(unsupported(
            origin,
            format!(
                "partitioned meshes ($PartitionedEntities at line {}) are not supported",
                s.start
            ),
        ));
    }
    let mut raw = RawMesh::default();
    if let Some(s) = once("PhysicalNames")? {
        raw.names = parse_physical_names(&mut Body::new(origin, s))?;
    }
    let entities = match (version, once("Entities")?) {
        (Version::V41, Some(s)) => parse_entities(&mut Body::new(origin, s))?,
        _ => HashMap::new(),
    };
    let nodes = once("Nodes")?.ok_or_else(|| invalid(origin, "no $Nodes section".to_string()))?;
    let elements =
        once("Elements")?.ok_or_else(|| invalid(origin, "no $Elements section".to_string()))?;
    let (mut nb, mut eb) = (Body::new(origin, nodes), Body::new(origin, elements));
    match version {
        Version::V41 => {
            raw.nodes = parse_nodes41(&mut nb)?;
            raw.elements = parse_elements41(&mut eb, &entities)?;
        }
        Version::V22 => {
            raw.nodes = parse_nodes22(&mut nb)?;
            raw.elements = parse_elements22(&mut eb)?;
        }
    }
    Ok(raw)
}

/// The version from the `$MeshFormat` header; refuses binary files before anything else is
/// read.
pub(super) fn mesh_format(text: &str, origin: &str) -> Result<Version> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    if !lines.any(|(_, l)| l == "$MeshFormat") {
        return Err(invalid(
            origin,
            "not a gmsh .msh file (no $MeshFormat section)".to_string(),
        ));
    }
    let (line, header) = lines
        .find(|(_, l)| !l.is_empty())
        .ok_or_else(|| malformed(origin, "MeshFormat", 1, "the file ends after $MeshFormat"))?;
    let fields: Vec<&str> = header.split_whitespace().collect();
    let [version, file_type, _data_size] = fields[..] else {
        return Err(malformed(
            origin,
            "MeshFormat",
            line,
            format!(
                "expected `version file-type data-size`, found `{}`",
                snippet(header)
            ),
        ));
    };
    if file_type != "0" {
        return Err(unsupported(
            origin,
            "binary .msh files are not supported; save it as ASCII (Mesh.Binary = 0)".to_string(),
        ));
    }
    match version {
        "4.1" => Ok(Version::V41),
        "2" | "2.0" | "2.1" | "2.2" => Ok(Version::V22),
        _ => Err(unsupported(
            origin,
            format!("msh format version {version} is not supported (ASCII 4.1 or 2.2 are read)"),
        )),
    }
}

pub(super) fn split_sections<'a>(text: &'a str, origin: &str) -> Result<Vec<Section<'a>>> {
    let mut sections = Vec::new();
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    while let Some((start, line)) = lines.next() {
        let Some(name) = line.strip_prefix('$') else {
            continue; // text outside sections is ignored, as gmsh does
        };
        let end_tag = format!("$End{name}");
        let mut body = Vec::new();
        let mut end = None;
        for (n, l) in lines.by_ref() {
            if l == end_tag {
                end = Some(n);
                break;
            }
            if !l.is_empty() {
                body.push((n, l));
            }
        }
        let end =
            end.ok_or_else(|| malformed(origin, name, start, format!("no {end_tag} closes it")))?;
        sections.push(Section {
            name,
            start,
            end,
            body,
        });
    }
    Ok(sections)
}

/// A cursor over the non-empty lines of one section.
pub(super) struct Body<'a> {
    origin: &'a str,
    section: &'a str,
    lines: &'a [Line<'a>],
    pos: usize,
    end: usize,
}

impl<'a> Body<'a> {
    fn new(origin: &'a str, s: &'a Section<'a>) -> Self {
        Body {
            origin,
            section: s.name,
            lines: &s.body,
            pos: 0,
            end: s.end,
        }
    }

    fn error(&self, line: usize, detail: impl Into<String>) -> GmshError {
        malformed(self.origin, self.section, line, detail)
    }

    fn next(&mut self, what: &str) -> Result<Line<'a>> {
        let line = self.lines.get(self.pos).copied();
        self.pos += 1;
        line.ok_or_else(|| {
            self.error(
                self.end,
                format!("the section ends where {what} was expected"),
            )
        })
    }

    /// The next line as a token reader.
    fn tokens(&mut self, what: &'a str) -> Result<Tokens<'a>> {
        let (line, text) = self.next(what)?;
        Ok(Tokens {
            origin: self.origin,
            section: self.section,
            line,
            what,
            it: text.split_whitespace(),
        })
    }

    /// The next line as exactly `n` integers.
    fn ints(&mut self, what: &'a str, n: usize) -> Result<(usize, Vec<i64>)> {
        let mut t = self.tokens(what)?;
        let values = (0..n).map(|_| t.int()).collect::<Result<Vec<_>>>()?;
        t.done()?;
        Ok((t.line, values))
    }

    /// A count read from the file at `line`: `value`, or the error `negative` below zero.
    fn count(&self, line: usize, value: i64, negative: &str) -> Result<usize> {
        usize::try_from(value).map_err(|_| self.error(line, negative))
    }

    /// The next line as a single count: `what` says which (for errors), `negative` is the error
    /// when it is below zero.
    fn count_line(&mut self, what: &'a str, negative: &str) -> Result<usize> {
        let (line, header) = self.ints(what, 1)?;
        self.count(line, header[0], negative)
    }

    /// The records of a msh 2.2 `$Nodes` or `$Elements` section: a line with their count
    /// (`count` says which, `negative` is the error when it is below zero), then one record a
    /// line, laid out as `record` says and read by `parse`, then the section's end.
    fn records22<T>(
        &mut self,
        count: &'a str,
        negative: &str,
        record: &'a str,
        mut parse: impl FnMut(&Self, Tokens<'a>) -> Result<T>,
    ) -> Result<Vec<T>> {
        let n = self.count_line(count, negative)?;
        let mut records = Vec::with_capacity(n.min(self.remaining()));
        for _ in 0..n {
            let t = self.tokens(record)?;
            records.push(parse(self, t)?);
        }
        self.finish()?;
        Ok(records)
    }

    /// Lines not consumed yet (bounds preallocation by counts read from the file).
    fn remaining(&self) -> usize {
        self.lines.len().saturating_sub(self.pos)
    }

    fn finish(&self) -> Result<()> {
        match self.lines.get(self.pos) {
            Some(&(line, text)) => {
                Err(self.error(line, format!("unexpected extra line `{}`", snippet(text))))
            }
            None => Ok(()),
        }
    }
}

/// Whitespace-separated fields of one line.
pub(super) struct Tokens<'a> {
    origin: &'a str,
    section: &'a str,
    line: usize,
    what: &'a str,
    it: std::str::SplitWhitespace<'a>,
}

impl<'a> Tokens<'a> {
    fn error(&self, detail: String) -> GmshError {
        malformed(self.origin, self.section, self.line, detail)
    }

    fn field(&mut self) -> Result<&'a str> {
        let what = self.what;
        self.it
            .next()
            .ok_or_else(|| self.error(format!("too few fields in {what}")))
    }

    fn int(&mut self) -> Result<i64> {
        let f = self.field()?;
        f.parse::<i64>()
            .map_err(|_| self.error(format!("`{}` is not an integer", snippet(f))))
    }

    fn count(&mut self) -> Result<usize> {
        let v = self.int()?;
        usize::try_from(v).map_err(|_| self.error(format!("negative count {v}")))
    }

    fn float(&mut self) -> Result<f64> {
        let f = self.field()?;
        match f.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(format!("`{}` is not a finite number", snippet(f)))),
        }
    }

    /// The remaining fields as integers.
    fn rest_ints(&mut self) -> Result<Vec<i64>> {
        let mut out = Vec::new();
        while let Some(f) = self.it.next() {
            let v = f
                .parse::<i64>()
                .map_err(|_| self.error(format!("`{}` is not an integer", snippet(f))))?;
            out.push(v);
        }
        Ok(out)
    }

    fn done(&mut self) -> Result<()> {
        match self.it.next() {
            Some(f) => Err(self.error(format!(
                "unexpected field `{}` in {}",
                snippet(f),
                self.what
            ))),
            None => Ok(()),
        }
    }
}

pub(super) fn parse_physical_names(b: &mut Body) -> Result<HashMap<(u8, i64), String>> {
    let n = b.count_line("the number of names", "negative count")?;
    let mut names = HashMap::new();
    for _ in 0..n {
        let (line, text) = b.next("`dimension tag \"name\"`")?;
        let parsed = split_name_line(text);
        let (dim, tag, name) = parsed.ok_or_else(|| {
            b.error(
                line,
                format!(
                    "expected `dimension tag \"name\"`, found `{}`",
                    snippet(text)
                ),
            )
        })?;
        let dim = dimension(dim).ok_or_else(|| b.error(line, format!("bad dimension {dim}")))?;
        names.insert((dim, tag), name.to_string());
    }
    b.finish()?;
    Ok(names)
}

pub(super) fn split_name_line(text: &str) -> Option<(i64, i64, &str)> {
    let (dim, rest) = text.split_once(char::is_whitespace)?;
    let (tag, rest) = rest.trim_start().split_once(char::is_whitespace)?;
    let name = rest.trim().strip_prefix('"')?.strip_suffix('"')?;
    Some((dim.parse().ok()?, tag.parse().ok()?, name))
}

pub(super) fn dimension(d: i64) -> Option<u8> {
    u8::try_from(d).ok().filter(|d| *d <= 3)
}

/// msh 4.1 `$Entities`: (dimension, entity tag) → physical tags.
pub(super) fn parse_entities(b: &mut Body) -> Result<HashMap<(u8, i64), Vec<i64>>> {
    let (line, counts) = b.ints("`numPoints numCurves numSurfaces numVolumes`", 4)?;
    let mut map = HashMap::new();
    for (dim, &count) in counts.iter().enumerate() {
        let count = b.count(line, count, "negative entity count")?;
        let dim = dim as u8;
        for _ in 0..count {
            let mut t = b.tokens("an entity line")?;
            let tag = t.int()?;
            let coords = if dim == 0 { 3 } else { 6 };
            for _ in 0..coords {
                t.float()?;
            }
            let n = t.count()?;
            let physicals = (0..n).map(|_| t.int()).collect::<Result<Vec<_>>>()?;
            if dim > 0 {
                let nb = t.count()?;
                for _ in 0..nb {
                    t.int()?;
                }
            }
            t.done()?;
            map.insert((dim, tag), physicals);
        }
    }
    b.finish()?;
    Ok(map)
}

pub(super) fn parse_nodes41(b: &mut Body) -> Result<Vec<RawNode>> {
    let (line, header) = b.ints("`numEntityBlocks numNodes minNodeTag maxNodeTag`", 4)?;
    let (blocks, total) = (header[0], header[1]);
    let mut nodes = Vec::with_capacity(b.remaining());
    for _ in 0..blocks.max(0) {
        let (bline, block) = b.ints("`entityDim entityTag parametric numNodesInBlock`", 4)?;
        if block[2] != 0 {
            return Err(unsupported(
                b.origin,
                format!(
                    "parametric node coordinates ($Nodes block at line {bline}) are not supported; save with Mesh.SaveParametric = 0"
                ),
            ));
        }
        let n = b.count(bline, block[3], "negative node count")?;
        let mut tags = Vec::with_capacity(n.min(b.remaining()));
        for _ in 0..n {
            tags.push(b.ints("a node tag", 1)?.1[0]);
        }
        for tag in tags {
            let mut t = b.tokens("`x y z`")?;
            let xyz = [t.float()?, t.float()?, t.float()?];
            t.done()?;
            nodes.push(node(b, t.line, tag, xyz)?);
        }
    }
    check_block_total(b, line, blocks, total, nodes.len(), "nodes")?;
    b.finish()?;
    Ok(nodes)
}

/// A msh 4.1 `$Nodes` / `$Elements` header's count of blocks and of `what` (nodes or
/// elements) against the `found` ones its blocks held; `line` is the header's line.
fn check_block_total(
    b: &Body,
    line: usize,
    blocks: i64,
    total: i64,
    found: usize,
    what: &str,
) -> Result<()> {
    if i64::try_from(found).ok() != Some(total) || blocks < 0 {
        return Err(b.error(
            line,
            format!("the header announces {total} {what}, the blocks hold {found}"),
        ));
    }
    Ok(())
}

pub(super) fn parse_nodes22(b: &mut Body) -> Result<Vec<RawNode>> {
    let (count, negative) = ("the number of nodes", "negative node count");
    b.records22(count, negative, "`node-number x y z`", |b, mut t| {
        let tag = t.int()?;
        let xyz = [t.float()?, t.float()?, t.float()?];
        t.done()?;
        node(b, t.line, tag, xyz)
    })
}

pub(super) fn node(b: &Body, line: usize, tag: i64, xyz: [f64; 3]) -> Result<RawNode> {
    if tag < 1 {
        return Err(b.error(line, format!("node tag {tag} is not positive")));
    }
    if xyz[2] != 0.0 {
        return Err(invalid(
            b.origin,
            format!(
                "node {tag} has z = {}; only planar meshes in the z = 0 plane are read",
                xyz[2]
            ),
        ));
    }
    Ok(RawNode {
        tag,
        xy: [xyz[0], xyz[1]],
    })
}

pub(super) fn parse_elements41(
    b: &mut Body,
    entities: &HashMap<(u8, i64), Vec<i64>>,
) -> Result<Vec<RawElement>> {
    let (line, header) = b.ints(
        "`numEntityBlocks numElements minElementTag maxElementTag`",
        4,
    )?;
    let (blocks, total) = (header[0], header[1]);
    let mut elements = Vec::with_capacity(b.remaining());
    for _ in 0..blocks.max(0) {
        let (bline, block) = b.ints("`entityDim entityTag elementType numElementsInBlock`", 4)?;
        let dim = dimension(block[0])
            .ok_or_else(|| b.error(bline, format!("bad dimension {}", block[0])))?;
        let physicals = entities.get(&(dim, block[1])).cloned().unwrap_or_default();
        let etype = block[2];
        let n = b.count(bline, block[3], "negative element count")?;
        for _ in 0..n {
            let mut t = b.tokens("`elementTag nodeTag …`")?;
            let tag = t.int()?;
            let nodes = t.rest_ints()?;
            let element = RawElement {
                line: t.line,
                tag,
                etype,
                dim,
                physicals: physicals.clone(),
                nodes,
            };
            check_node_count(b, &element)?;
            elements.push(element);
        }
    }
    check_block_total(b, line, blocks, total, elements.len(), "elements")?;
    b.finish()?;
    Ok(elements)
}

pub(super) fn parse_elements22(b: &mut Body) -> Result<Vec<RawElement>> {
    let (count, negative) = ("the number of elements", "negative element count");
    let record = "`elm-number elm-type number-of-tags tags… nodes…`";
    b.records22(count, negative, record, |b, mut t| {
        let (tag, etype, ntags) = (t.int()?, t.int()?, t.count()?);
        let tags = (0..ntags).map(|_| t.int()).collect::<Result<Vec<_>>>()?;
        let nodes = t.rest_ints()?;
        let line = t.line;
        let (dim, _, _) = element_type(etype).ok_or_else(|| {
            unsupported(
                b.origin,
                format!("element type {etype} (line {line}) is not supported"),
            )
        })?;
        let physicals = tags
            .first()
            .copied()
            .filter(|&p| p != 0)
            .into_iter()
            .collect();
        let element = RawElement {
            line,
            tag,
            etype,
            dim,
            physicals,
            nodes,
        };
        check_node_count(b, &element)?;
        Ok(element)
    })
}

pub(super) fn check_node_count(b: &Body, e: &RawElement) -> Result<()> {
    match element_type(e.etype) {
        Some((_, n, name)) if n != e.nodes.len() => Err(b.error(
            e.line,
            format!(
                "element {} is a {name} but lists {} nodes",
                e.tag,
                e.nodes.len()
            ),
        )),
        _ => Ok(()),
    }
}

/// (dimension, number of nodes, name) of the gmsh element types.
pub(super) fn element_type(etype: i64) -> Option<(u8, usize, &'static str)> {
    let info = match etype {
        1 => (1, 2, "2-node line"),
        2 => (2, 3, "3-node triangle"),
        3 => (2, 4, "4-node quadrangle"),
        4 => (3, 4, "4-node tetrahedron"),
        5 => (3, 8, "8-node hexahedron"),
        6 => (3, 6, "6-node prism"),
        7 => (3, 5, "5-node pyramid"),
        8 => (1, 3, "3-node line"),
        9 => (2, 6, "6-node triangle"),
        10 => (2, 9, "9-node quadrangle"),
        11 => (3, 10, "10-node tetrahedron"),
        12 => (3, 27, "27-node hexahedron"),
        13 => (3, 18, "18-node prism"),
        14 => (3, 14, "14-node pyramid"),
        15 => (0, 1, "1-node point"),
        16 => (2, 8, "8-node quadrangle"),
        17 => (3, 20, "20-node hexahedron"),
        18 => (3, 15, "15-node prism"),
        19 => (3, 13, "13-node pyramid"),
        20 => (2, 9, "9-node triangle"),
        21 => (2, 10, "10-node triangle"),
        22 => (2, 12, "12-node triangle"),
        23 => (2, 15, "15-node triangle"),
        24 => (2, 15, "15-node incomplete triangle"),
        25 => (2, 21, "21-node triangle"),
        26 => (1, 4, "4-node line"),
        27 => (1, 5, "5-node line"),
        28 => (1, 6, "6-node line"),
        _ => return None,
    };
    Some(info)
}

pub(super) fn type_name(etype: i64) -> String {
    match element_type(etype) {
        Some((_, _, name)) => format!("{name} (type {etype})"),
        None => format!("element type {etype}"),
    }
}
