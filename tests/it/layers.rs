//! The import graph of `src/` (issue 16): which top-level modules each one names
//! (`crate::<module>` outside comments and test modules). No module may sit in a circle with
//! `scene` (it is read by everything above it), and the model layers (`bsdf`, `material`,
//! `texture`, `light`, `mesh`, `film`, `scene`, `params`, `limits`) never reach `integrator`,
//! `photon`, `accel` or `tools`.
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Top-level module -> the top-level modules its code names.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let mut deps: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut stack = vec![Path::new("src").to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            if p.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = p.strip_prefix("src").unwrap();
            let top = rel.iter().next().unwrap().to_string_lossy();
            let top = top.trim_end_matches(".rs").to_string();
            let text = std::fs::read_to_string(&p).unwrap();
            // Test modules may reach anywhere: stop at the first one.
            let code = text.split("#[cfg(test)]").next().unwrap();
            for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
                for (i, _) in line.match_indices("crate::") {
                    let name: String = line[i + 7..]
                        .chars()
                        .take_while(|c| c.is_ascii_lowercase() || *c == '_')
                        .collect();
                    if !name.is_empty() && name != top {
                        deps.entry(top.clone()).or_default().insert(name);
                    }
                }
            }
        }
    }
    deps
}

fn reach(deps: &BTreeMap<String, BTreeSet<String>>, from: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![from.to_string()];
    while let Some(m) = stack.pop() {
        for d in deps.get(&m).into_iter().flatten() {
            if seen.insert(d.clone()) {
                stack.push(d.clone());
            }
        }
    }
    seen
}

#[test]
fn no_circle_through_scene_and_no_arrow_up_from_the_model() {
    let deps = graph();
    assert!(
        deps.contains_key("scene") && deps.contains_key("integrator"),
        "{deps:?}"
    );
    let below_scene = reach(&deps, "scene");
    let circle: Vec<&String> = below_scene
        .iter()
        .filter(|m| reach(&deps, m).contains("scene"))
        .collect();
    assert!(circle.is_empty(), "in a circle with scene: {circle:?}");
    let model = [
        "bsdf", "material", "texture", "light", "mesh", "film", "scene", "params", "limits",
    ];
    for m in model {
        let up: Vec<String> = reach(&deps, m)
            .into_iter()
            .filter(|d| ["integrator", "photon", "accel", "tools"].contains(&d.as_str()))
            .collect();
        assert!(up.is_empty(), "{m} reaches {up:?}");
    }
}
