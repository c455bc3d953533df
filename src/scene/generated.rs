//! Scenes made by program rather than read from a file: `n` spheres on a
//! floor, the same on every run. The bench's cost-against-object-count
//! series and its big scenes are made of them, and so are the tests that
//! need many objects (a hierarchy, reflections) without a file.

/// A scene of `n` spheres of radius 0.2 scattered on a floor, seen from
/// above at `width × height`, phong, two lights. The floor's side grows
/// like √n so the spheres keep their density; positions come from a fixed
/// xorshift sequence, so the scene is the same on every run.
pub fn spheres_on_floor(n: usize, width: u32, height: u32) -> String {
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15 ^ n as u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let half = 2.0 * (n as f64).sqrt().max(1.0);
    let mut xml = String::with_capacity(200 * n + 1000);
    xml.push_str("<scene>\n  <plane><color red=\"0.8\" green=\"0.8\" blue=\"0.75\"/>");
    xml.push_str("<material ka=\"0.2\" kd=\"0.5\" ks=\"0.1\" m=\"5\"/>");
    xml.push_str("<transformation><rotate-x angle=\"1.5707963267948966\"/><translate y=\"1\"/></transformation></plane>\n");
    for _ in 0..n {
        let (x, z) = ((2.0 * next() - 1.0) * half, next() * 2.0 * half);
        let (r, g, b) = (0.1 + 0.9 * next(), 0.1 + 0.9 * next(), 0.1 + 0.9 * next());
        xml.push_str(&format!(
            "  <sphere><color red=\"{r:.3}\" green=\"{g:.3}\" blue=\"{b:.3}\"/><material ka=\"0.2\" kd=\"0.6\" ks=\"0.4\" m=\"30\"/><transformation><scale factor=\"0.2\"/><translate x=\"{x:.4}\" y=\"0.8\" z=\"{z:.4}\"/></transformation></sphere>\n"
        ));
    }
    // The camera backs off as the floor grows, keeping it in view.
    xml.push_str(&format!(
        "  <light x=\"-10\" y=\"-20\" z=\"-10\"/>\n  <light x=\"15\" y=\"-10\" z=\"5\"><color red=\"0.5\" green=\"0.5\" blue=\"0.6\"/></light>\n  <camera width=\"{width}\" height=\"{height}\" eyeDistance=\"2\"><transformation><rotate-x angle=\"-0.5\"/><translate y=\"{}\" z=\"{}\"/></transformation></camera>\n  <model type=\"phong\"/>\n</scene>\n",
        -0.8 * half,
        -0.6 * half
    ));
    xml
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_scenes_load_with_n_spheres() {
        for n in [1, 10, 1000] {
            let text = spheres_on_floor(n, 80, 60);
            let scene = super::super::parse(&text, std::path::Path::new("gen.xml")).unwrap();
            assert_eq!(scene.objects.len(), n + 1);
            assert_eq!(text, spheres_on_floor(n, 80, 60), "deterministic");
        }
    }
}
