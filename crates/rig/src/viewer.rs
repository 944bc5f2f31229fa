//! `view.html`: a page that shows the input rig and a simplified level side by side in
//! three.js, playing the animation in sync, with the documents' materials and textures, a
//! level selector, a slider per morph target and a wireframe toggle (`viewer/view.js`).
//!
//! The page takes a list of levels ([`ViewInput::levels`]): the input first, then the
//! simplified levels, finest first (one today; a LOD chain later). Each is a `.glb`.
//!
//! Chromium refuses ES-module imports and `fetch` from `file://`, and a user opens the
//! page by double-clicking it. So every level goes in the page, as base64 in a JSON
//! `<script>` block parsed by `GLTFLoader.parse` with no fetch, and three.js comes from
//! one of two places; neither is desal's source tree (a library belongs in a package):
//! - **By default, the network.** The import map names the pinned version's files on a
//!   CDN ([`ThreePin::url`]), and its `integrity` key gives each file's sha384, so the
//!   browser runs those exact bytes or nothing. three's modules import each other
//!   relatively (`./three.core.js`, `../utils/SkeletonUtils.js`); those imports resolve
//!   to the CDN too, and have integrity entries of their own. The page needs the network.
//! - **Offline, a local npm `three` package** ([`view_html`]'s `three`: the folder
//!   `node_modules/three`, from `DESAL_THREE` through [`three_dir_from_env`]). Every file
//!   is checked against the pinned sha384 first, then inlined as today's page was: the
//!   import map's targets are `data:` URLs of the modules, which Chromium, Firefox and
//!   Safari import from any origin. A `data:` URL has no folder to resolve a relative
//!   import against, so the modules' relative imports are rewritten to the import map's
//!   bare names ([`MODULES`]); nothing else in them changes. three's MIT licence goes in
//!   an HTML comment.
//!
//! The pin lives in one file, `viewer/three-pin.json` (version, CDN, sha384 per file),
//! compiled in ([`pin`]). `.ci/run` installs that version for the checks, and
//! `tests/gltf/three-pin.mjs` checks the pin against the package's files (and rewrites
//! the hashes after an upgrade, with `--write`).

use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use crate::RigError;

/// The pin's text (see the module doc).
const PIN_JSON: &str = include_str!("../viewer/three-pin.json");

/// The environment variable that asks for an offline page: the folder of a local npm
/// `three` package (`.../node_modules/three`) whose files `view.html` inlines.
pub const THREE_ENV: &str = "DESAL_THREE";

/// The modules the page imports, as `(path in the package, import-map name)`: the names
/// three's own documentation uses (`three`, `three/addons/...`). Every path is pinned.
pub const MODULES: &[(&str, &str)] = &[
    ("build/three.core.js", "three/build/three.core.js"),
    ("build/three.module.js", "three"),
    ("examples/jsm/utils/BufferGeometryUtils.js", "three/addons/utils/BufferGeometryUtils.js"),
    ("examples/jsm/utils/SkeletonUtils.js", "three/addons/utils/SkeletonUtils.js"),
    ("examples/jsm/loaders/GLTFLoader.js", "three/addons/loaders/GLTFLoader.js"),
    ("examples/jsm/controls/OrbitControls.js", "three/addons/controls/OrbitControls.js"),
];

/// three's licence file: pinned and inlined (as a comment) with the modules offline.
const LICENSE: &str = "LICENSE";

/// The pinned npm `three`: `viewer/three-pin.json`, parsed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ThreePin {
    /// The exact npm version (`0.187.0`).
    pub version: String,
    /// The npm CDN's base URL, ending in `/`; a file's URL is `{cdn}three@{version}/{path}`.
    pub cdn: String,
    /// Every file the page uses, `(path in the package, "sha384-<base64>")`, sorted by path.
    pub files: Vec<(String, String)>,
}

impl ThreePin {
    /// Parses the pin's JSON: `version`, `cdn` and `sha384` (an object of path → hash).
    pub fn parse(json: &str) -> Result<Self, String> {
        let value: serde_json::Value = serde_json::from_str(json).map_err(|e| e.to_string())?;
        let text = |key: &str| {
            value[key].as_str().map(str::to_owned).ok_or_else(|| format!("`{key}` is not a string"))
        };
        let (version, cdn) = (text("version")?, text("cdn")?);
        let hashes = value["sha384"].as_object().ok_or("`sha384` is not an object")?;
        let files = hashes
            .iter()
            .map(|(path, hash)| match hash.as_str() {
                Some(h) if h.starts_with("sha384-") => Ok((path.clone(), h.to_owned())),
                _ => Err(format!("sha384 of {path} is not a \"sha384-...\" string")),
            })
            .collect::<Result<Vec<_>, _>>()?;
        if !cdn.ends_with('/') {
            return Err(format!("`cdn` must end in '/': {cdn}"));
        }
        Ok(Self { version, cdn, files })
    }

    /// The CDN URL of a file of the pinned package.
    pub fn url(&self, path: &str) -> String {
        format!("{}three@{}/{path}", self.cdn, self.version)
    }

    /// The pinned `sha384-<base64>` of a file, if the pin has it.
    pub fn sha384(&self, path: &str) -> Option<&str> {
        self.files.iter().find(|(p, _)| p == path).map(|(_, h)| h.as_str())
    }
}

/// The pin compiled into this build (`viewer/three-pin.json`).
pub fn pin() -> &'static ThreePin {
    static PIN: LazyLock<ThreePin> = LazyLock::new(|| {
        ThreePin::parse(PIN_JSON).expect("viewer/three-pin.json parses (a unit test checks it)")
    });
    &PIN
}

/// The `three` folder `DESAL_THREE` names, if it is set and not empty: the one place
/// desal reads the variable. `None` means the default, network page.
pub fn three_dir_from_env() -> Option<PathBuf> {
    std::env::var_os(THREE_ENV).filter(|v| !v.is_empty()).map(PathBuf::from)
}

/// What the page's three.js is, for an output folder's key: the pinned version and
/// where it loads from (the network, or inlined from a local package). A local package
/// that passes the check is the pinned bytes, so its folder is not part of it.
pub fn three_key(three: Option<&Path>) -> String {
    let from = if three.is_some() { "inlined" } else { "cdn" };
    format!("three@{} {from}", pin().version)
}

/// The page's own script.
const VIEW_JS: &str = include_str!("../viewer/view.js");

/// One level the page shows: a rig as a `.glb` and its name in the page.
#[derive(Debug, Clone, Copy)]
pub struct ViewLevel<'a> {
    /// The level's name (`input`, `simplified`, `LOD 1`, ...).
    pub label: &'a str,
    /// The rig's `.glb` bytes (a whole document: its materials and textures are drawn).
    pub glb: &'a [u8],
}

/// What the page shows.
#[derive(Debug, Clone, Copy)]
pub struct ViewInput<'a> {
    /// The page title (the dataset's name).
    pub title: &'a str,
    /// The input rig (shown on the left), then at least one simplified level, finest
    /// first (one at a time on the right, picked by the page's level selector).
    pub levels: &'a [ViewLevel<'a>],
    /// One line under the two views.
    pub caption: &'a str,
}

/// The page (see the module doc). [`RigError::Output`] when `input` has fewer than two
/// levels (the input and a simplified one). With `three` `None` it loads the pinned three.js from
/// the CDN (the network is needed to view it); with the folder of a local npm `three`
/// package it inlines that package's files, after checking each against the pin
/// ([`RigError::Three`] names a missing or different file and the version to install).
pub fn view_html(input: &ViewInput<'_>, three: Option<&Path>) -> Result<String, RigError> {
    view_html_pinned(input, three, pin())
}

fn view_html_pinned(input: &ViewInput<'_>, three: Option<&Path>, pin: &ThreePin) -> Result<String, RigError> {
    if input.levels.len() < 2 {
        return Err(RigError::Output(format!(
            "view.html needs the input and at least one simplified level, not {} level(s)",
            input.levels.len()
        )));
    }
    let (import_map, licence, load_error) = match three {
        None => (
            cdn_import_map(pin),
            String::new(),
            format!(
                "three.js {v} could not be loaded from {base} (this page needs the network, and the files must match their pinned sha384); \
                 for a page that works offline, run desal again with DESAL_THREE set to the node_modules/three folder of `npm install three@{v}`",
                v = pin.version,
                base = pin.url(""),
            ),
        ),
        Some(dir) => {
            let licence = String::from_utf8_lossy(&read_pinned(dir, pin, LICENSE)?).into_owned();
            (
                inlined_import_map(dir, pin)?,
                format!(
                    "<!-- three.js {}, inlined below:\n{}-->\n",
                    pin.version,
                    licence.replace("--", "- -")
                ),
                format!("three.js {} (inlined) could not be loaded", pin.version),
            )
        }
    };
    let levels: Vec<serde_json::Value> = input
        .levels
        .iter()
        .map(|level| serde_json::json!({"label": level.label, "glb": base64(level.glb)}))
        .collect();
    let data = serde_json::json!({"levels": levels, "caption": input.caption});
    debug_assert!(!VIEW_JS.contains("</script"), "view.js must not close its script element");
    Ok(format!(
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
  #bar label {{ white-space: nowrap; }}
  #morphs {{ position: absolute; left: 0.6em; bottom: 3.8em; display: flex; flex-direction: column; gap: 0.2em;
            padding: 0.4em 0.6em; font-size: 12px; background: rgba(244, 244, 242, 0.85); border-radius: 4px; }}
  #morphs input {{ width: 7em; vertical-align: middle; }}
</style>
{licence}<script type="importmap">{import_map}</script>
</head>
<body>
<div class="label" id="label-full">input</div>
<div class="label" id="label-simplified">simplified</div>
<canvas id="canvas"></canvas>
<div id="morphs" hidden></div>
<div id="bar">
  <button id="play" type="button">pause</button>
  <label><input id="wireframe" type="checkbox"> wireframe</label>
  <label>level <select id="level"></select></label>
  <span id="caption">loading...</span>
</div>
<script id="desal-data" type="application/json">{data}</script>
<script type="module" onerror="{onerror}">
{script}
</script>
</body>
</html>
"#,
        generator = env!("CARGO_PKG_VERSION"),
        three = pin.version,
        title = escape_html(input.title),
        import_map = script_json(&import_map),
        data = script_json(&data),
        onerror = escape_html(&module_error_handler(&load_error)),
        script = VIEW_JS,
    ))
}

/// The module script's `onerror`: the browser fires it when a module cannot be fetched
/// (no network, or bytes that fail their integrity check), before any of view.js runs;
/// it puts `message` under the views and in the test hook's `error`.
fn module_error_handler(message: &str) -> String {
    let message = serde_json::Value::from(message).to_string();
    format!(
        "window.desalView = {{ ready: false, error: {message} }}; document.getElementById('caption').textContent = {message};"
    )
}

/// The default import map: every module's pinned CDN URL, with its sha384 under the URL
/// it is fetched from (also the relatively imported ones, which resolve to the same URLs).
fn cdn_import_map(pin: &ThreePin) -> serde_json::Value {
    let imports: serde_json::Map<String, serde_json::Value> =
        MODULES.iter().map(|&(path, name)| (name.to_owned(), pin.url(path).into())).collect();
    let integrity: serde_json::Map<String, serde_json::Value> = MODULES
        .iter()
        .map(|&(path, _)| {
            let hash = pin.sha384(path).unwrap_or_else(|| panic!("{path} is imported but not pinned"));
            (pin.url(path), hash.into())
        })
        .collect();
    serde_json::json!({ "imports": imports, "integrity": integrity })
}

/// The offline import map: every module inlined as a `data:` URL, read from the local
/// package `dir` and checked against the pin.
fn inlined_import_map(dir: &Path, pin: &ThreePin) -> Result<serde_json::Value, RigError> {
    let mut imports = serde_json::Map::new();
    for &(path, name) in MODULES {
        let bytes = read_pinned(dir, pin, path)?;
        let source =
            String::from_utf8(bytes).map_err(|_| three_error(dir, pin, format!("{path} is not UTF-8")))?;
        let source = inline_module(path, source).map_err(|problem| three_error(dir, pin, problem))?;
        imports.insert(
            name.to_owned(),
            format!("data:text/javascript;base64,{}", base64(source.as_bytes())).into(),
        );
    }
    Ok(serde_json::json!({ "imports": imports }))
}

/// The bytes of the local package's file `path`, if they are the pinned ones. The folder
/// is the user's and trusted; the file is read as a regular file only.
fn read_pinned(dir: &Path, pin: &ThreePin, path: &str) -> Result<Vec<u8>, RigError> {
    let expected = pin.sha384(path).unwrap_or_else(|| panic!("{path} is used but not pinned"));
    let file = dir.join(path);
    let bytes = desal_io::file::read_regular_file(&file).map_err(|e| three_error(dir, pin, e.to_string()))?;
    let found = sha384(&bytes);
    if found != expected {
        let installed =
            installed_version(dir).map_or_else(String::new, |v| format!("; that folder holds three {v}"));
        return Err(three_error(
            dir,
            pin,
            format!(
                "{} is not the file of three {} ({found}, pinned {expected}{installed})",
                file.display(),
                pin.version
            ),
        ));
    }
    Ok(bytes)
}

/// The `version` in the local package's `package.json`, for the error message only.
fn installed_version(dir: &Path) -> Option<String> {
    let bytes = desal_io::file::read_regular_file(&dir.join("package.json")).ok()?;
    let value: serde_json::Value = serde_json::from_slice(&bytes).ok()?;
    value["version"].as_str().map(str::to_owned)
}

fn three_error(dir: &Path, pin: &ThreePin, problem: String) -> RigError {
    RigError::Three { dir: dir.to_owned(), version: pin.version.clone(), problem }
}

/// `"sha384-<base64>"` of `bytes`, as Subresource Integrity writes it.
fn sha384(bytes: &[u8]) -> String {
    use sha2::Digest;
    format!("sha384-{}", base64(sha2::Sha384::digest(bytes).as_slice()))
}

/// A module's source with its relative imports renamed to import-map names; `Err` names
/// an import of a file the page does not inline.
fn inline_module(path: &str, mut source: String) -> Result<String, String> {
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
            .ok_or_else(|| format!("{path} imports {target}, which the page does not inline"))?;
        source.replace_range(range, name);
    }
    Ok(source)
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

    /// The modules' import statements as three 0.187 writes them (a relative import of
    /// the core, the addons' `three` and `../utils/...`), in a fake package with its pin.
    fn fake_package(dir: &Path) -> ThreePin {
        let source = |path: &str| {
            match path {
            "build/three.module.js" => "import { A } from './three.core.js';\nexport { B } from './three.core.js';\n".to_owned(),
            "examples/jsm/loaders/GLTFLoader.js" => "import {\n\tA\n} from 'three';\nimport { c } from '../utils/BufferGeometryUtils.js';\nimport { d } from '../utils/SkeletonUtils.js';\n".to_owned(),
            "build/three.core.js" => "export const A = 1;\n".to_owned(),
            LICENSE => "The MIT License\n".to_owned(),
            other => format!("import {{ A }} from 'three';\n// {other}\n"),
        }
        };
        let mut files = Vec::new();
        for path in MODULES.iter().map(|(p, _)| *p).chain([LICENSE]) {
            let file = dir.join(path);
            std::fs::create_dir_all(file.parent().unwrap()).unwrap();
            std::fs::write(&file, source(path)).unwrap();
            files.push((path.to_owned(), sha384(source(path).as_bytes())));
        }
        std::fs::write(dir.join("package.json"), r#"{"name": "three", "version": "0.0.1"}"#).unwrap();
        files.sort();
        ThreePin { version: "0.0.1".into(), cdn: "https://cdn.example/npm/".into(), files }
    }

    const LEVELS: [ViewLevel<'static>; 2] =
        [ViewLevel { label: "input", glb: b"full" }, ViewLevel { label: "simplified", glb: b"simplified" }];
    const INPUT: ViewInput<'static> = ViewInput { title: "a<b", levels: &LEVELS, caption: "</script>" };

    /// The page's data: every level, in order, its label and its bytes; a page of one
    /// level is refused.
    #[test]
    fn the_page_takes_a_list_of_levels_input_first() {
        let three = [
            ViewLevel { label: "input", glb: b"a" },
            ViewLevel { label: "LOD 1", glb: b"bb" },
            ViewLevel { label: "LOD 2", glb: b"ccc" },
        ];
        let html = view_html(&ViewInput { title: "t", levels: &three, caption: "c" }, None).unwrap();
        let opening = "<script id=\"desal-data\" type=\"application/json\">";
        let start = html.find(opening).unwrap() + opening.len();
        let end = start + html[start..].find("</script>").unwrap();
        let data: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
        let levels: Vec<(&str, &str)> = data["levels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| (l["label"].as_str().unwrap(), l["glb"].as_str().unwrap()))
            .collect();
        assert_eq!(levels, [("input", "YQ=="), ("LOD 1", "YmI="), ("LOD 2", "Y2Nj")]);
        let one = view_html(&ViewInput { title: "t", levels: &three[..1], caption: "c" }, None).unwrap_err();
        assert!(one.to_string().contains("at least one simplified level"), "{one}");
    }

    /// The JSON of the page's import map.
    fn import_map(html: &str) -> serde_json::Value {
        let opening = "<script type=\"importmap\">";
        let start = html.find(opening).expect("an import map") + opening.len();
        let end = start + html[start..].find("</script>").unwrap();
        serde_json::from_str(&html[start..end]).unwrap()
    }

    /// SHA-384 of "abc", FIPS 180-2 appendix D.1 (cb00753f...134c825a7), as Subresource
    /// Integrity writes it (base64).
    #[test]
    fn sha384_matches_the_fips_vector() {
        assert_eq!(sha384(b"abc"), "sha384-ywB1P0WjXou1oD1pmsZQBycsMqsO3tFjGotgWkP/W+2AhgcroefMI1i67KE0yCWn");
    }

    /// The pin compiled in names exactly the page's modules and the licence, with hashes of
    /// SHA-384's 48 bytes, and a CDN URL of that exact version.
    #[test]
    fn the_pin_covers_every_module_and_the_licence() {
        let pin = pin();
        let mut wanted: Vec<&str> = MODULES.iter().map(|(p, _)| *p).chain([LICENSE]).collect();
        wanted.sort();
        assert_eq!(pin.files.iter().map(|(p, _)| p.as_str()).collect::<Vec<_>>(), wanted);
        use base64::Engine;
        for (path, hash) in &pin.files {
            let digest = base64::engine::general_purpose::STANDARD.decode(&hash["sha384-".len()..]).unwrap();
            assert_eq!(digest.len(), 48, "{path}");
        }
        assert!(
            pin.version.split('.').all(|n| n.parse::<u32>().is_ok()),
            "an exact version: {}",
            pin.version
        );
        assert_eq!(
            pin.url("build/three.module.js"),
            format!("https://cdn.jsdelivr.net/npm/three@{}/build/three.module.js", pin.version)
        );
    }

    #[test]
    fn a_pin_without_hashes_or_with_another_algorithm_is_refused() {
        assert!(ThreePin::parse(r#"{"version": "1.0.0", "cdn": "https://x/"}"#).is_err());
        let sha256 = r#"{"version": "1.0.0", "cdn": "https://x/", "sha384": {"a.js": "sha256-AAAA"}}"#;
        assert!(ThreePin::parse(sha256).unwrap_err().contains("a.js"));
    }

    /// The default page imports every module from the pinned URL, and the import map's
    /// integrity holds the pinned hash of each URL the page fetches: the mapped modules
    /// and those three imports relatively (`three.core.js`, the addons' utils).
    #[test]
    fn the_default_page_loads_each_module_from_the_cdn_with_its_pinned_hash() {
        let html = view_html(&INPUT, None).unwrap();
        let map = import_map(&html);
        let pin = pin();
        for &(path, name) in MODULES {
            let url = pin.url(path);
            assert_eq!(map["imports"][name], url.as_str(), "{name}");
            assert_eq!(map["integrity"][&url], pin.sha384(path).unwrap(), "{url}");
        }
        assert_eq!(map["integrity"].as_object().unwrap().len(), MODULES.len());
        assert!(!html.contains("data:text/javascript"));
        assert!(html.contains(&format!("npm install three@{}", pin.version)), "the offline hint");
    }

    /// Offline, every module is a `data:` URL importing only import-map names (a relative
    /// import left over would not resolve against a `data:` URL), the rest unchanged, and
    /// the licence rides along.
    #[test]
    fn an_offline_page_inlines_the_checked_modules_with_relative_imports_renamed() {
        let dir = tempfile::tempdir().unwrap();
        let pin = fake_package(dir.path());
        let html = view_html_pinned(&INPUT, Some(dir.path()), &pin).unwrap();
        let map = import_map(&html);
        assert!(map.get("integrity").is_none());
        let names: Vec<&str> = MODULES.iter().map(|(_, n)| *n).collect();
        let (mut rewritten, mut imports) = (0, 0);
        for &(path, name) in MODULES {
            let url = map["imports"][name].as_str().unwrap();
            let payload = url.strip_prefix("data:text/javascript;base64,").expect("inlined");
            use base64::Engine;
            let source =
                String::from_utf8(base64::engine::general_purpose::STANDARD.decode(payload).unwrap())
                    .unwrap();
            for range in import_specifiers(&source) {
                assert!(names.contains(&&source[range.clone()]), "{path} imports {}", &source[range]);
                imports += 1;
            }
            let original = std::fs::read_to_string(dir.path().join(path)).unwrap();
            rewritten += usize::from(original != source);
        }
        assert_eq!(rewritten, 2, "three.module.js and GLTFLoader.js import relatively");
        // three.module.js: core twice; GLTFLoader: three and two utils; the utils and
        // OrbitControls: three.
        assert_eq!(imports, 2 + 3 + 1 + 1 + 1);
        assert!(html.contains("<!-- three.js 0.0.1, inlined below:\nThe MIT License\n-->"));
        assert!(html.contains(&base64(b"full")) && html.contains(&base64(b"simplified")));
        assert!(html.contains("<title>desal: a&lt;b</title>"));
        assert_eq!(html.matches("</script>").count(), 3, "the caption cannot close a script");
        assert!(!html.contains("://cdn"), "no network reference");
    }

    /// A local package of another version is refused before anything is inlined; the
    /// error names the file, the pinned version and the folder's own.
    #[test]
    fn a_local_file_that_differs_from_the_pin_is_refused_naming_it_and_the_version() {
        let dir = tempfile::tempdir().unwrap();
        let pin = fake_package(dir.path());
        let changed = dir.path().join("examples/jsm/utils/SkeletonUtils.js");
        std::fs::write(&changed, "import { A } from 'three'; // 0.0.2\n").unwrap();
        let error = view_html_pinned(&INPUT, Some(dir.path()), &pin).unwrap_err().to_string();
        assert!(error.contains(&format!("{} is not the file of three 0.0.1", changed.display())), "{error}");
        assert!(error.contains("that folder holds three 0.0.1"), "{error}");
        assert!(error.contains("npm install three@0.0.1"), "{error}");
    }

    #[test]
    fn a_missing_local_package_is_refused_naming_the_file_and_the_version() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no-three");
        let error = view_html(&INPUT, Some(&missing)).unwrap_err().to_string();
        assert!(error.contains(&missing.join(LICENSE).display().to_string()), "{error}");
        assert!(error.contains(&format!("npm install three@{}", pin().version)), "{error}");
    }

    #[test]
    fn import_statements_are_found_and_comments_are_not() {
        let source = "import { A } from 'three';\n// loaded from 'https://x/y.bin'\n} from \"./b.js\";\n";
        let found: Vec<&str> = import_specifiers(source).into_iter().map(|r| &source[r]).collect();
        assert_eq!(found, ["three", "./b.js"]);
    }

    #[test]
    fn the_key_tells_the_cdn_page_from_the_inlined_one() {
        assert_ne!(three_key(None), three_key(Some(Path::new("x"))));
        assert_eq!(three_key(Some(Path::new("x"))), three_key(Some(Path::new("y"))));
    }
}
