//! `view.html`: a page that shows the full and the simplified rig side by side in
//! three.js, playing the animation in sync, with a wireframe toggle (`viewer/view.js`).
//!
//! Chromium refuses ES-module imports and `fetch` from `file://`, and a user opens the
//! page by double-clicking it. So the page is one self-contained file:
//! - three.js (npm `three`, vendored byte for byte under `crates/rig/viewer/three/` and
//!   embedded in the binary) goes in an import map whose targets are `data:` URLs of the
//!   modules, which Chromium, Firefox and Safari import from any origin. A `data:` URL
//!   has no folder to resolve a relative import against, so the modules' relative
//!   imports (`'./three.core.js'`, `'../utils/SkeletonUtils.js'`) are rewritten to the
//!   import map's bare names ([`MODULES`]); nothing else in them changes.
//! - Both rigs go in as base64 in a JSON `<script>` block and are parsed by
//!   `GLTFLoader.parse`, with no fetch.
//!
//! The vendored files are also written next to the page (`viewer/three/`, with three's
//! MIT licence and version) as the readable, licensed sources of the code it inlines.
//! CI checks that they equal the pinned npm package's files (`tests/gltf/vendored.mjs`).

/// The version of npm `three` vendored here (its `package.json`'s, checked by CI).
pub const THREE_VERSION: &str = "0.187.0";

/// One vendored file of npm `three`: its path inside the package, and its bytes.
#[derive(Debug, Clone, Copy)]
pub struct VendoredFile {
    pub path: &'static str,
    pub bytes: &'static [u8],
}

macro_rules! vendored {
    ($($path:literal),* $(,)?) => {
        &[$(VendoredFile { path: $path, bytes: include_bytes!(concat!("../viewer/three/", $path)) }),*]
    };
}

/// Every vendored file of `three`, as the npm package holds them, plus `VERSION`.
pub const VENDORED: &[VendoredFile] = vendored![
    "LICENSE",
    "VERSION",
    "build/three.core.js",
    "build/three.module.js",
    "examples/jsm/loaders/GLTFLoader.js",
    "examples/jsm/utils/BufferGeometryUtils.js",
    "examples/jsm/utils/SkeletonUtils.js",
    "examples/jsm/controls/OrbitControls.js",
];

/// The modules the page imports, as `(path in the package, import-map name)`: the names
/// three's own documentation uses (`three`, `three/addons/...`).
pub const MODULES: &[(&str, &str)] = &[
    ("build/three.core.js", "three/build/three.core.js"),
    ("build/three.module.js", "three"),
    ("examples/jsm/utils/BufferGeometryUtils.js", "three/addons/utils/BufferGeometryUtils.js"),
    ("examples/jsm/utils/SkeletonUtils.js", "three/addons/utils/SkeletonUtils.js"),
    ("examples/jsm/loaders/GLTFLoader.js", "three/addons/loaders/GLTFLoader.js"),
    ("examples/jsm/controls/OrbitControls.js", "three/addons/controls/OrbitControls.js"),
];

/// The page's own script.
const VIEW_JS: &str = include_str!("../viewer/view.js");

/// What the page shows.
#[derive(Debug, Clone, Copy)]
pub struct ViewInput<'a> {
    /// The page title (the dataset's name).
    pub title: &'a str,
    /// The full rig as a `.glb` (left).
    pub full_glb: &'a [u8],
    /// The simplified rig as a `.glb` (right): the bytes of `simplified.glb`.
    pub simplified_glb: &'a [u8],
    /// One line under the two views.
    pub caption: &'a str,
}

/// The bytes of a vendored file by its path in the package.
fn vendored(path: &str) -> &'static [u8] {
    VENDORED.iter().find(|f| f.path == path).map(|f| f.bytes).expect("every module is vendored")
}

/// The page, self-contained (see the module doc).
pub fn view_html(input: &ViewInput<'_>) -> String {
    let imports: serde_json::Map<String, serde_json::Value> = MODULES
        .iter()
        .map(|&(path, name)| {
            let source = inline_module(path);
            (name.to_owned(), format!("data:text/javascript;base64,{}", base64(source.as_bytes())).into())
        })
        .collect();
    let import_map = serde_json::json!({ "imports": imports });
    let data = serde_json::json!({
        "full": base64(input.full_glb),
        "simplified": base64(input.simplified_glb),
        "caption": input.caption,
    });
    debug_assert!(!VIEW_JS.contains("</script"), "view.js must not close its script element");
    format!(
        r#"<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="desal {generator}, three.js {three}">
<title>desal: {title}</title>
<style>
  html, body {{ margin: 0; height: 100%; font: 14px system-ui, sans-serif; color: #222; background: #f4f4f2; }}
  #canvas {{ display: block; width: 100%; height: calc(100% - 3.2em); }}
  .label {{ position: absolute; top: 0.6em; width: 50%; text-align: center; pointer-events: none; }}
  #label-full {{ left: 0; }}
  #label-simplified {{ left: 50%; }}
  #bar {{ display: flex; gap: 1.2em; align-items: center; height: 3.2em; padding: 0 1em; box-sizing: border-box; }}
</style>
<script type="importmap">{import_map}</script>
</head>
<body>
<div class="label" id="label-full">full (input)</div>
<div class="label" id="label-simplified">simplified</div>
<canvas id="canvas"></canvas>
<div id="bar">
  <button id="play" type="button">pause</button>
  <label><input id="wireframe" type="checkbox"> wireframe</label>
  <span id="caption">loading...</span>
</div>
<script id="desal-data" type="application/json">{data}</script>
<script type="module">
{script}
</script>
</body>
</html>
"#,
        generator = env!("CARGO_PKG_VERSION"),
        three = THREE_VERSION,
        title = escape_html(input.title),
        import_map = script_json(&import_map),
        data = script_json(&data),
        script = VIEW_JS,
    )
}

/// A vendored module's source with its relative imports renamed to import-map names.
fn inline_module(path: &str) -> String {
    let mut source = String::from_utf8(vendored(path).to_vec()).expect("three's modules are UTF-8");
    let folder = path.rsplit_once('/').map_or("", |(folder, _)| folder);
    // Back to front, so the earlier ranges stay valid.
    for range in import_specifiers(&source).into_iter().rev() {
        let specifier = &source[range.clone()];
        if !specifier.starts_with('.') {
            continue;
        }
        let target = resolve(folder, specifier);
        let name = MODULES
            .iter()
            .find(|(p, _)| *p == target)
            .map(|(_, name)| *name)
            .unwrap_or_else(|| panic!("{path} imports {target}, which is not vendored"));
        source.replace_range(range, name);
    }
    source
}

/// The byte ranges of the specifiers of a module's static `import ... from '...'` and
/// `export ... from '...'` statements (three writes one per line, the `from` on the
/// statement's last line, which starts with `import`, `export` or `}`); comments that
/// merely say "from '...'" are not statements.
fn import_specifiers(source: &str) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut line_start = 0;
    for line in source.split_inclusive('\n') {
        let trimmed = line.trim_start();
        if ["import ", "export ", "} from"].iter().any(|p| trimmed.starts_with(p)) {
            for quote in ['\'', '"'] {
                if let Some(at) = line.find(&format!("from {quote}")) {
                    let start = at + "from ".len() + 1;
                    if let Some(len) = line[start..].find(quote) {
                        out.push(line_start + start..line_start + start + len);
                    }
                }
            }
        }
        line_start += line.len();
    }
    out
}

/// `relative` (`./a.js`, `../b/c.js`) against `folder` (`build`, `examples/jsm/loaders`).
fn resolve(folder: &str, relative: &str) -> String {
    let mut parts: Vec<&str> = folder.split('/').filter(|p| !p.is_empty()).collect();
    for part in relative.split('/') {
        match part {
            "." => {}
            ".." => {
                parts.pop();
            }
            p => parts.push(p),
        }
    }
    parts.join("/")
}

/// JSON that is safe inside a `<script>` element (no `</script>`, no `<!--`).
fn script_json(value: &serde_json::Value) -> String {
    value.to_string().replace('<', "\\u003c")
}

fn escape_html(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Standard base64 (RFC 4648 §4, with padding).
fn base64(bytes: &[u8]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RFC 4648 §10's test vectors.
    #[test]
    fn base64_matches_the_rfc_vectors() {
        let vectors = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
        ];
        for (plain, encoded) in vectors {
            assert_eq!(base64(plain.as_bytes()), encoded, "{plain:?}");
        }
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }

    #[test]
    fn relative_imports_resolve_against_the_module_folder() {
        assert_eq!(resolve("build", "./three.core.js"), "build/three.core.js");
        assert_eq!(
            resolve("examples/jsm/loaders", "../utils/SkeletonUtils.js"),
            "examples/jsm/utils/SkeletonUtils.js"
        );
    }

    /// After inlining, every module imports only import-map names: a relative import
    /// left over would fail to resolve against a `data:` URL in the browser.
    #[test]
    fn inlined_modules_import_only_import_map_names() {
        let names: Vec<&str> = MODULES.iter().map(|(_, n)| *n).collect();
        let (mut rewritten, mut imports) = (0, 0);
        for &(path, _) in MODULES {
            let original = String::from_utf8(vendored(path).to_vec()).unwrap();
            let source = inline_module(path);
            for range in import_specifiers(&source) {
                assert!(names.contains(&&source[range.clone()]), "{path} imports {}", &source[range]);
                imports += 1;
            }
            rewritten += usize::from(original != source);
        }
        assert_eq!(rewritten, 2, "three.module.js and GLTFLoader.js import relatively");
        // three.module.js: core twice; GLTFLoader: three and two utils; the utils and
        // OrbitControls: three.
        assert_eq!(imports, 2 + 3 + 1 + 1 + 1);
    }

    #[test]
    fn import_statements_are_found_and_comments_are_not() {
        let source = "import { A } from 'three';\n// loaded from 'https://x/y.bin'\n} from \"./b.js\";\n";
        let found: Vec<&str> = import_specifiers(source).into_iter().map(|r| &source[r]).collect();
        assert_eq!(found, ["three", "./b.js"]);
    }

    #[test]
    fn the_version_file_is_the_vendored_version() {
        assert_eq!(std::str::from_utf8(vendored("VERSION")).unwrap().trim(), THREE_VERSION);
    }

    #[test]
    fn the_page_carries_both_rigs_and_no_network_reference() {
        let html = view_html(&ViewInput {
            title: "a<b",
            full_glb: b"full",
            simplified_glb: b"simplified",
            caption: "</script>",
        });
        assert!(html.contains(&base64(b"full")) && html.contains(&base64(b"simplified")));
        assert!(html.contains("<title>desal: a&lt;b</title>"));
        assert_eq!(html.matches("</script>").count(), 3, "the caption cannot close a script");
        assert!(!html.contains("http://") && !html.contains("https://"));
    }
}
