//! The scene format as an XML Schema (XSD 1.0), written from
//! [`super::grammar`]: what `rayoflight schema` prints, for editors'
//! completion, hover documentation and validation.
//!
//! Each element and attribute carries its `xs:documentation` (meaning,
//! range, default). Numbers are restricted to what the loader reads: a
//! finite decimal (no `INF`, `NaN`, hexadecimal or comma); integers are
//! ASCII digits with an optional `+`. `<scene>` holds exactly one camera and
//! at most one model among any number of objects and lights, in any order:
//! a content model XSD 1.0 can say deterministically as "things, then the
//! camera or the model first, then things, then the other". What XSD 1.0
//! cannot say (a `scale` with `factor` and an axis, a singular
//! transformation, an image over 2^28 pixels, the count limits) is said in
//! the documentation, and only the loader refuses it.

use super::grammar::{self, Attribute, Element, Presence, Repeat, Value};
use std::fmt::Write;

/// The schema's text.
pub fn xsd() -> String {
    let mut out = String::new();
    let w = &mut out;
    line(w, 0, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    line(
        w,
        0,
        &format!(
            "<!-- The RayOfLight {} scene format. Written by `rayoflight schema` from the loader's own tables. -->",
            env!("CARGO_PKG_VERSION")
        ),
    );
    line(
        w,
        0,
        r#"<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema" elementFormDefault="unqualified">"#,
    );
    documentation(
        w,
        1,
        "A RayOfLight scene: spheres, planes, lights, one camera and an illumination model. \
         World space is right-handed: x to the right, y down, z forward. \
         A scene may name this schema: <?xml-model href=\"rayoflight.xsd\"?>, or \
         xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
         xsi:noNamespaceSchemaLocation=\"rayoflight.xsd\" on <scene>.",
    );
    let root = grammar::element("scene").expect("the grammar has a root");
    element_declaration(w, 1, root);
    number_types(w);
    for element in grammar::ELEMENTS {
        complex_type(w, element);
    }
    line(w, 0, "</xs:schema>");
    out
}

fn line(w: &mut String, depth: usize, text: &str) {
    let _ = writeln!(w, "{:width$}{text}", "", width = 2 * depth);
}

fn documentation(w: &mut String, depth: usize, text: &str) {
    line(w, depth, "<xs:annotation>");
    line(
        w,
        depth + 1,
        &format!(
            "<xs:documentation>{}</xs:documentation>",
            quick_xml::escape::partial_escape(text)
        ),
    );
    line(w, depth, "</xs:annotation>");
}

/// `<xs:element name=… type=…>` with its documentation (the element's own
/// type has the same name).
fn element_declaration(w: &mut String, depth: usize, element: &Element) {
    element_occurring(w, depth, element, "");
}

fn element_occurring(w: &mut String, depth: usize, element: &Element, occurs: &str) {
    line(
        w,
        depth,
        &format!(
            r#"<xs:element name="{0}" type="{0}"{occurs}>"#,
            element.name
        ),
    );
    documentation(w, depth + 1, &element.documentation());
    line(w, depth, "</xs:element>");
}

fn child(name: &str) -> &'static Element {
    grammar::element(name).expect("every child is an element of the grammar")
}

/// The simple types of numbers: `number` (finite), `nonNegativeNumber`,
/// `positiveNumber`.
fn number_types(w: &mut String) {
    line(w, 1, r#"<xs:simpleType name="number">"#);
    documentation(
        w,
        2,
        "A finite decimal number: an optional sign, digits with an optional point, an optional \
         exponent (1, -2.5, .5, 3., 1e-3, 2E+5). Not INF, NaN, hexadecimal or a decimal comma.",
    );
    line(w, 2, r#"<xs:restriction base="xs:double">"#);
    line(
        w,
        3,
        r#"<xs:pattern value="[+\-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+\-]?[0-9]+)?"/>"#,
    );
    // What overflows to infinity (1e999) is not finite.
    line(
        w,
        3,
        r#"<xs:minInclusive value="-1.7976931348623157E308"/>"#,
    );
    line(w, 3, r#"<xs:maxInclusive value="1.7976931348623157E308"/>"#);
    line(w, 2, "</xs:restriction>");
    line(w, 1, "</xs:simpleType>");
    for (name, facet, doc) in [
        (
            "nonNegativeNumber",
            "minInclusive",
            "A finite number, 0 or more.",
        ),
        (
            "positiveNumber",
            "minExclusive",
            "A finite number greater than 0.",
        ),
    ] {
        line(w, 1, &format!(r#"<xs:simpleType name="{name}">"#));
        documentation(w, 2, doc);
        line(w, 2, r#"<xs:restriction base="number">"#);
        line(w, 3, &format!(r#"<xs:{facet} value="0"/>"#));
        line(w, 2, "</xs:restriction>");
        line(w, 1, "</xs:simpleType>");
    }
}

/// The named simple type of a number value.
fn number_type(min: Option<f64>, min_exclusive: bool) -> &'static str {
    match (min, min_exclusive) {
        (None, _) => "number",
        (Some(0.0), false) => "nonNegativeNumber",
        (Some(0.0), true) => "positiveNumber",
        (Some(m), _) => unreachable!("the grammar has no number bound {m} but 0"),
    }
}

/// The element's type: its children's content model and its attributes.
fn complex_type(w: &mut String, element: &Element) {
    line(
        w,
        1,
        &format!(r#"<xs:complexType name="{}">"#, element.name),
    );
    let things: Vec<&str> = element
        .children
        .iter()
        .copied()
        .filter(|c| !is_single(element, c))
        .collect();
    match element.repeat {
        _ if element.children.is_empty() => {}
        Repeat::EachOnce => {
            line(w, 2, "<xs:all>");
            for name in element.children {
                element_occurring(w, 3, child(name), r#" minOccurs="0""#);
            }
            line(w, 2, "</xs:all>");
        }
        Repeat::Any => {
            line(w, 2, r#"<xs:choice minOccurs="0" maxOccurs="unbounded">"#);
            for name in element.children {
                element_declaration(w, 3, child(name));
            }
            line(w, 2, "</xs:choice>");
        }
        Repeat::Scene { one, at_most_one } => {
            // things* ((one things* (at_most_one things*)?) | (at_most_one things* one things*))
            let things = |w: &mut String, depth| {
                line(
                    w,
                    depth,
                    r#"<xs:choice minOccurs="0" maxOccurs="unbounded">"#,
                );
                for name in &things {
                    element_declaration(w, depth + 1, child(name));
                }
                line(w, depth, "</xs:choice>");
            };
            line(w, 2, "<xs:sequence>");
            things(w, 3);
            line(w, 3, "<xs:choice>");
            line(w, 4, "<xs:sequence>");
            element_declaration(w, 5, child(one));
            things(w, 5);
            line(w, 5, r#"<xs:sequence minOccurs="0">"#);
            element_declaration(w, 6, child(at_most_one));
            things(w, 6);
            line(w, 5, "</xs:sequence>");
            line(w, 4, "</xs:sequence>");
            line(w, 4, "<xs:sequence>");
            element_declaration(w, 5, child(at_most_one));
            things(w, 5);
            element_declaration(w, 5, child(one));
            things(w, 5);
            line(w, 4, "</xs:sequence>");
            line(w, 3, "</xs:choice>");
            line(w, 2, "</xs:sequence>");
        }
    }
    for name in element.attributes {
        let attribute = grammar::attribute(element.name, name)
            .expect("every attribute of the loader's lists is in the grammar's table");
        attribute_declaration(w, attribute);
    }
    line(w, 1, "</xs:complexType>");
}

/// Whether `name` is the scene's one camera or its one model.
fn is_single(element: &Element, name: &str) -> bool {
    match element.repeat {
        Repeat::Scene { one, at_most_one } => name == one || name == at_most_one,
        _ => false,
    }
}

fn attribute_declaration(w: &mut String, attribute: &Attribute) {
    let presence = match attribute.presence {
        Presence::Required => r#" use="required""#.to_owned(),
        Presence::Default(value) => format!(r#" default="{value}""#),
        Presence::Optional => String::new(),
    };
    let doc = attribute.documentation();
    let named_type = match attribute.value {
        Value::Number { min, min_exclusive } => Some(number_type(min, min_exclusive)),
        _ => None,
    };
    match named_type {
        Some(t) => {
            line(
                w,
                2,
                &format!(
                    r#"<xs:attribute name="{}" type="{t}"{presence}>"#,
                    attribute.name
                ),
            );
            documentation(w, 3, &doc);
        }
        None => {
            line(
                w,
                2,
                &format!(r#"<xs:attribute name="{}"{presence}>"#, attribute.name),
            );
            documentation(w, 3, &doc);
            line(w, 3, "<xs:simpleType>");
            match attribute.value {
                Value::Integer { min, max } => {
                    line(w, 4, r#"<xs:restriction base="xs:nonNegativeInteger">"#);
                    // Digits and an optional +: not -0.
                    line(w, 5, r#"<xs:pattern value="\+?[0-9]+"/>"#);
                    line(w, 5, &format!(r#"<xs:minInclusive value="{min}"/>"#));
                    line(w, 5, &format!(r#"<xs:maxInclusive value="{max}"/>"#));
                }
                Value::Choice(names) => {
                    line(w, 4, r#"<xs:restriction base="xs:token">"#);
                    for name in names {
                        line(w, 5, &format!(r#"<xs:enumeration value="{name}"/>"#));
                    }
                }
                Value::Number { .. } => unreachable!("numbers have a named type"),
            }
            line(w, 4, "</xs:restriction>");
            line(w, 3, "</xs:simpleType>");
        }
    }
    line(w, 2, "</xs:attribute>");
}

#[cfg(test)]
mod tests {
    //! The grammar's table against the loader: for every attribute, its
    //! presence, default and range are the loader's.
    use super::super::{LoadErrorKind, parse};
    use super::grammar::{self, Presence, Value};
    use std::path::Path;

    /// A scene with every element and every attribute (but `scale`'s
    /// `factor`, which excludes the axes: `UNIFORM` has it).
    const FULL: &str = r#"<scene>
<sphere><color red="0.5" green="0.5" blue="0.5"/><material ka="0.3" kd="0.5" ks="0.1" m="4"/>
<transformation><translate x="1" y="2" z="3"/><rotate-x angle="0.1"/><rotate-y angle="0.2"/><rotate-z angle="0.3"/><scale x="2" y="3" z="4"/></transformation></sphere>
<plane/>
<light x="1" y="-4" z="2"><color red="1" green="1" blue="1"/></light>
<camera width="8" height="6" eyeDistance="2"><transformation/></camera>
<model type="whitted" depth="3"/>
</scene>"#;
    const UNIFORM: &str = r#"<scene><sphere><transformation><scale factor="2"/></transformation></sphere>
<camera width="8" height="6" eyeDistance="2"/></scene>"#;

    /// `text` with `attribute` of the first `<element …>` set to `value`
    /// (`None`: removed).
    fn with(text: &str, element: &str, attribute: &str, value: Option<&str>) -> String {
        let start = text
            .find(&format!("<{element} "))
            .expect("the element is there");
        let end = start + text[start..].find('>').expect("a tag ends");
        let tag = &text[start..end];
        let at = tag
            .find(&format!(" {attribute}=\""))
            .expect("the attribute is there");
        let close =
            at + 1 + attribute.len() + 2 + tag[at + attribute.len() + 3..].find('"').unwrap();
        let new = match value {
            Some(v) => format!("{} {attribute}=\"{v}\"{}", &tag[..at], &tag[close + 1..]),
            None => format!("{}{}", &tag[..at], &tag[close + 1..]),
        };
        format!("{}{new}{}", &text[..start], &text[end..])
    }

    #[test]
    fn every_attribute_is_required_defaulted_and_ranged_as_the_loader_does() {
        let load = |text: &str| parse(text, Path::new("t.xml"));
        assert!(load(FULL).is_ok() && load(UNIFORM).is_ok());
        for a in grammar::ATTRIBUTES {
            let base = if a.name == "factor" { UNIFORM } else { FULL };
            let (e, n) = (a.element, a.name);
            let set = |v: &str| load(&with(base, e, n, Some(v)));
            match a.presence {
                Presence::Required => match load(&with(base, e, n, None)) {
                    Err(err) => assert_eq!(
                        err.kind,
                        LoadErrorKind::MissingAttribute {
                            element: e,
                            attribute: n
                        },
                        "{e} {n}"
                    ),
                    Ok(_) => panic!("{e} {n}: the loader does not require it"),
                },
                Presence::Default(value) => {
                    assert_eq!(load(&with(base, e, n, None)), set(value), "{e} {n}");
                }
                Presence::Optional => {
                    assert!(load(&with(base, e, n, None)).is_ok(), "{e} {n}");
                }
            }
            match a.value {
                Value::Number { min: None, .. } => {
                    assert!(set("-1e300").is_ok() && set("1e300").is_ok(), "{e} {n}");
                }
                Value::Number {
                    min: Some(min),
                    min_exclusive,
                } => {
                    assert_eq!(min, 0.0);
                    assert_eq!(set("0").is_ok(), !min_exclusive, "{e} {n}");
                    assert!(set("-1e-300").is_err() && set("1e-300").is_ok(), "{e} {n}");
                }
                Value::Integer { min, max } => {
                    // The image-size rule stops the camera's sides first.
                    if e != "camera" {
                        assert!(set(&max.to_string()).is_ok(), "{e} {n}");
                    }
                    assert!(set(&(max + 1).to_string()).is_err(), "{e} {n}");
                    assert!(set(&min.to_string()).is_ok(), "{e} {n}");
                    if min > 0 {
                        assert!(set(&(min - 1).to_string()).is_err(), "{e} {n}");
                    }
                }
                Value::Choice(names) => {
                    for name in names {
                        assert!(set(name).is_ok(), "{e} {n} {name}");
                    }
                    assert!(set("other").is_err(), "{e} {n}");
                }
            }
        }
    }

    #[test]
    fn the_table_names_every_attribute_and_child_of_the_loader() {
        for element in grammar::ELEMENTS {
            for name in element.attributes {
                assert!(grammar::attribute(element.name, name).is_some(), "{name}");
            }
            for child in element.children {
                assert!(grammar::element(child).is_some(), "{child}");
            }
        }
        for a in grammar::ATTRIBUTES {
            let element = grammar::element(a.element).expect("its element");
            assert!(
                element.attributes.contains(&a.name),
                "{} {}",
                a.element,
                a.name
            );
        }
        // Every element is reachable from the root, and the schema names it.
        let xsd = super::xsd();
        for element in grammar::ELEMENTS {
            assert!(xsd.contains(&format!("name=\"{}\"", element.name)));
        }
    }
}
