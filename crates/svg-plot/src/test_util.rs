//! Helpers of the unit tests: a well-formedness check of the SVG documents, element and attribute
//! extraction, and a sample chart.

use std::collections::BTreeSet;

use crate::layout::Frame;
use crate::style::K;
use crate::{Chart, PALETTE, Pt, Series};

/// Checks that tags are balanced and properly nested, and that `&` only starts an entity.
pub(crate) fn assert_well_formed(svg: &str) {
    let body = svg.strip_prefix("<?xml version=\"1.0\" encoding=\"UTF-8\"?>").expect("XML declaration");
    let mut stack: Vec<String> = Vec::new();
    let mut rest = body;
    while let Some(start) = rest.find('<') {
        let text = &rest[..start];
        assert!(!text.contains('>'), "stray '>' in text {text:?}");
        check_entities(text);
        let end = rest[start..].find('>').expect("unterminated tag") + start;
        let tag = &rest[start + 1..end];
        assert!(!tag.contains('<'), "'<' inside tag {tag:?}");
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(stack.pop().as_deref(), Some(name.trim()), "mismatched closing tag");
        } else if !tag.ends_with('/') {
            let name = tag.split_whitespace().next().expect("tag name");
            stack.push(name.to_owned());
        }
        // Attribute values are quoted and contain no raw '&' outside entities.
        assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes in {tag:?}");
        check_entities(tag);
        rest = &rest[end + 1..];
    }
    assert!(rest.trim().is_empty());
    assert!(stack.is_empty(), "unclosed tags {stack:?}");
    assert!(stack.is_empty() && svg.starts_with("<?xml"), "document");
    assert!(!svg.contains("NaN") && !svg.contains("inf"), "non-finite number in the output:\n{svg}");
    assert!(!svg.chars().any(|c| c.is_control() && c != '\n'), "control character in the output");
}

pub(crate) fn check_entities(s: &str) {
    for (i, _) in s.match_indices('&') {
        let ent = &s[i..s[i..].find(';').map_or(s.len(), |e| i + e + 1)];
        assert!(["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"].contains(&ent), "bad entity {ent:?}");
    }
}

/// The elements `<name …/>` (or `<name …>`) of `svg`, as their attribute text.
pub(crate) fn elements<'a>(svg: &'a str, name: &str) -> Vec<&'a str> {
    let open = format!("<{name} ");
    svg.match_indices(&open)
        .map(|(i, _)| {
            let rest = &svg[i + open.len()..];
            &rest[..rest.find('>').unwrap_or(rest.len())]
        })
        .collect()
}

pub(crate) fn attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let at = format!(" {element}").find(&key)? + key.len() - 1;
    let rest = &element[at..];
    Some(&rest[..rest.find('"')?])
}

pub(crate) fn num(element: &str, name: &str) -> f64 {
    attr(element, name).and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("{name} in {element}"))
}

/// Vertices of the polylines (or polygons) of colour `color`, as separate pieces.
pub(crate) fn paths(svg: &str, name: &str, color: &str) -> Vec<Vec<(i32, i32)>> {
    let paint = if name == "polygon" { "fill" } else { "stroke" };
    elements(svg, name)
        .into_iter()
        .filter(|e| attr(e, paint) == Some(color))
        .map(|e| {
            attr(e, "points")
                .expect("points")
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').expect("x,y");
                    (x.parse().expect("x"), y.parse().expect("y"))
                })
                .collect()
        })
        .collect()
}

/// The `<text>` elements as (x, y, content).
pub(crate) fn texts(svg: &str) -> Vec<(i32, i32, String)> {
    svg.match_indices("<text ")
        .map(|(i, _)| {
            let rest = &svg[i..];
            let open_end = rest.find('>').expect("tag end");
            let tag = &rest[6..open_end];
            let content = &rest[open_end + 1..rest.find("</text>").expect("closing tag")];
            (num(tag, "x") as i32, num(tag, "y") as i32, content.trim().to_owned())
        })
        .collect()
}

pub(crate) fn sample_chart() -> Chart {
    let t: Vec<f64> = (0..10_000).map(|i| i as f64 * 0.002).collect();
    let truth: Vec<f64> = t.iter().map(|t| t.sin()).collect();
    let mut c = Chart::new("β <&> test", "time [s]", "β [rad]");
    c.add(Series::band(
        "SMF A",
        t.clone(),
        truth.iter().map(|v| v - 0.2).collect(),
        truth.iter().map(|v| v + 0.2).collect(),
        PALETTE[1],
    ));
    c.add(Series::dashed("SMF B", t.clone(), truth.iter().map(|v| v + 0.3).collect(), PALETTE[2]));
    c.add(Series::dashed("SMF B", t.clone(), truth.iter().map(|v| v - 0.3).collect(), PALETTE[2]));
    c.add(Series::line("truth", t.clone(), truth, PALETTE[0]));
    c.add(Series::markers("points", vec![1.0, 2.0], vec![0.5, -0.5], PALETTE[3]));
    c
}

/// Deterministic pseudo-random numbers in `[0, 1)`.
pub(crate) fn rng(mut state: u64) -> impl FnMut() -> f64 {
    move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Asserts that the drawn vertices `drawn` lie in the plot area and include, for every pixel
/// column (the decimation's bucket), the highest and the lowest of the points `(xs, ys)` (to a
/// drawing unit, for the rounding of the way there and back through the range fractions).
pub(crate) fn assert_extremes_drawn(f: &Frame, xs: &[f64], ys: &[f64], drawn: &[(i32, i32)], what: &str) {
    for &(x, y) in drawn {
        assert!((f.left..f.left + f.w).contains(&x) && (f.top..f.top + f.h).contains(&y), "({x}, {y}) outside");
    }
    let set: BTreeSet<(i32, i32)> = drawn.iter().copied().collect();
    let near = |(x, y): (i32, i32)| (-1..=1).any(|dx| (-1..=1).any(|dy| set.contains(&(x + dx, y + dy))));
    let cols = f64::from(f.w - 1) / f64::from(K);
    // Per bucket, the lowest and the highest point.
    let mut buckets: std::collections::BTreeMap<i64, (Pt, Pt)> = Default::default();
    for (&x, &y) in xs.iter().zip(ys) {
        let b = ((x - f.x.lo) / (f.x.hi - f.x.lo) * cols).round() as i64;
        let e = buckets.entry(b).or_insert(((x, y), (x, y)));
        if y < e.0.1 {
            e.0 = (x, y);
        }
        if y > e.1.1 {
            e.1 = (x, y);
        }
    }
    assert!(buckets.len() > 200, "{what}: the data spans {} columns", buckets.len());
    for (b, (low, high)) in buckets {
        assert!(near(f.pixel(low)) && near(f.pixel(high)), "{what}, column {b}: {low:?} or {high:?} not drawn");
    }
}
