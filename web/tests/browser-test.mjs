// The workbench in a real browser: Debian's Chromium, headless, driven by playwright-core, against the
// static build (tools/web.sh build → target/web) served on 127.0.0.1 by a small server of our own.
//
//   node web/tests/browser-test.mjs [--backend webgl2|webgpu] [--native-params p.json]
//                                                                 (tools/web.sh test runs it, once per backend)
//
// The site has two modules (web/index.html picks one): wgpu on WebGL2 (the default here; Chromium's
// SwiftShader through ANGLE) and wgpu on WebGPU (`--backend webgpu`: Dawn on Chromium's SwiftShader
// Vulkan, with the flags below, which present a WebGPU canvas headless — SwiftShader's GL does not
// share its images with Dawn, so the WebGL2 run's flags give WebGPU no canvas). The page is loaded
// with `?backend=…`, and the app's renderer must be that backend.
//
// Widgets are found by role and name in the app's mirror of egui's accessibility tree (#dualcal-a11y:
// eframe's web runner has no AccessKit adapter) and clicked on the canvas at their bounds; figures are
// read from the app's state (#dualcal-status, JSON). Checks: the page loads and opens the compiled-in
// example; the 3D view draws the robot (turning the "robot" checkbox off changes the picture, and
// the picture has many colours); Calibrate, stepped within the frames, finishes and the calibrated
// figures show; the exports download (parameters JSON, calibrated URDF, CSV, plots PNG); "Open
// dataset…" opens picked files, a dropped .zip opens, "Open URDF…" opens a URDF with a loose mesh
// file; a run stepped one iteration per frame advances live and Cancel stops it; no console errors.
// With --native-params, the browser's parameters must equal the native command line's within 1e-9
// relative. Writes target/web-test/{workbench.png,status.json,params-browser.json,metrics.json,…}.
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { launchChromium, serveSite } from "./harness.mjs";
import { fileURLToPath } from "node:url";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../..");
const site = process.env.DUALCAL_WEB_SITE ?? path.join(root, "target/web");
const out = process.env.DUALCAL_WEB_TEST_OUT ?? path.join(root, "target/web-test");
const args = process.argv.slice(2);
const option = (name) => (args.includes(name) ? args[args.indexOf(name) + 1] : null);
const nativeParams = option("--native-params");
const backend = option("--backend") ?? "webgl2";
if (!["webgl2", "webgpu"].includes(backend)) {
  console.error(`browser-test: --backend ${backend}: expected webgl2 or webgpu`);
  process.exit(2);
}
const REL_TOL = 1e-9;
const WIDTH = 1400;
const HEIGHT = 900;

fs.mkdirSync(out, { recursive: true });
let passed = 0;
const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? "ok  " : "FAIL"} ${what}`);
  if (ok) passed++;
  else failures.push(what);
};

// ---- the site on 127.0.0.1, and Chromium headless on the backend's software renderer -------------
const server = await serveSite(site);
const origin = server.origin;
// The page's address with the backend asked for, and more query parameters after it.
const base = `${origin}?backend=${backend}`;
const browser = await launchChromium(backend, { width: WIDTH, height: HEIGHT, acceptDownloads: true });
const { page } = browser;
const consoleErrors = [];
page.on("console", (m) => {
  if (m.type() === "error") consoleErrors.push(m.text());
});
page.on("pageerror", (e) => consoleErrors.push(`page error: ${e.message}`));

const status = async () => {
  const text = await page.locator("#dualcal-status").textContent();
  return text ? JSON.parse(text) : null;
};
const waitFor = async (what, predicate, timeoutMs) => {
  const t0 = Date.now();
  for (;;) {
    const s = await status().catch(() => null);
    if (s && predicate(s)) return s;
    if (s?.phase === "failed") throw new Error(`${what}: the app failed: ${JSON.stringify(s.errors)}`);
    if (Date.now() - t0 > timeoutMs) throw new Error(`${what}: timed out; last status ${JSON.stringify(s)}`);
    await page.waitForTimeout(50);
  }
};
const idleWith = (pred) => (s) => s.phase === "idle" && pred(s);

// A widget of the accessibility tree by role and name: its bounds, enabled state; clicked on the canvas.
const widget = (role, name) =>
  page.locator("#dualcal-a11y").getByRole(role, { name, exact: true, includeHidden: true }).first();
const clickWidget = async (role, name, timeoutMs = 20_000) => {
  const t0 = Date.now();
  for (;;) {
    const w = widget(role, name);
    if ((await w.count()) > 0 && (await w.getAttribute("aria-disabled")) !== "true") {
      const [x0, y0, x1, y1] = (await w.getAttribute("data-bounds")).split(" ").map(Number);
      await page.mouse.click((x0 + x1) / 2, (y0 + y1) / 2);
      return;
    }
    if (Date.now() - t0 > timeoutMs) throw new Error(`no enabled ${role} "${name}" in the accessibility tree`);
    await page.waitForTimeout(50);
  }
};
const frames = (n) => page.evaluate((n) => new Promise((resolve) => {
  const step = (k) => (k === 0 ? resolve() : requestAnimationFrame(() => step(k - 1)));
  step(n);
}), n);

// Pixels of a screenshot (decoded in the page: no PNG library here).
const pixels = (png) => page.evaluate(async (b64) => {
  const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  const bitmap = await createImageBitmap(new Blob([bytes], { type: "image/png" }));
  const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
  const ctx = canvas.getContext("2d");
  ctx.drawImage(bitmap, 0, 0);
  return Array.from(ctx.getImageData(0, 0, bitmap.width, bitmap.height).data);
}, png.toString("base64"));
const colours = (data) => {
  const set = new Set();
  for (let i = 0; i < data.length; i += 4) set.add((data[i] << 16) | (data[i + 1] << 8) | data[i + 2]);
  return set.size;
};
const differing = (a, b) => {
  let n = 0;
  for (let i = 0; i < a.length; i += 4) {
    if (Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]) > 24) n++;
  }
  return n / (a.length / 4);
};
const download = async (name) => {
  const pending = page.waitForEvent("download", { timeout: 20_000 });
  await clickWidget("button", name);
  const file = await pending;
  const saved = path.join(out, `download-${file.suggestedFilename()}`);
  await file.saveAs(saved);
  return { name: file.suggestedFilename(), bytes: fs.readFileSync(saved) };
};

const metrics = {};
try {
  // ---- the page loads and opens the compiled-in example ----------------------------------------
  const t0 = Date.now();
  await page.goto(base, { waitUntil: "load" });
  let s = await waitFor("opening the example", idleWith((s) => s.session), 120_000);
  metrics.page_ready_ms = Date.now() - t0;
  metrics.first_frame_ms = Number(await page.locator("#dualcal-status").getAttribute("data-first-frame-ms"));
  metrics.load_bytes = server.served();
  metrics.renderer = s.renderer;
  metrics.backend = backend;
  metrics.module = await page.evaluate(() => document.documentElement.dataset.module ?? null);
  check(s.errors.length === 0 && s.session.dataset === "/example",
    `the page opens the compiled-in example without errors (${s.status}; renderer ${s.renderer})`);
  const rendererPattern = { webgl2: /\bGl\b|WebGL/i, webgpu: /\bBrowserWebGpu\b|WebGPU/i }[backend];
  check(rendererPattern.test(s.renderer ?? "") && metrics.module === backend,
    `the page loaded the ${backend} module (${metrics.module}) and the app renders on it (${s.renderer})`);

  // ---- the 3D view draws the robot: the "robot" checkbox changes the picture ---------------------
  await frames(3);
  const withRobot = await pixels(await page.screenshot());
  await clickWidget("checkbox", "robot");
  await frames(3);
  const withoutRobot = await pixels(await page.screenshot());
  await clickWidget("checkbox", "robot");
  const robotPixels = differing(withRobot, withoutRobot);
  const colourCount = colours(withRobot);
  metrics.robot_pixels_fraction = robotPixels;
  check(robotPixels > 0.005 && colourCount > 1000,
    `the canvas draws the robot: ${(100 * robotPixels).toFixed(2)}% of the pixels change when it is hidden; ${colourCount} colours`);

  // ---- Calibrate: stepped within the frames (no threads), adaptive budget ------------------------
  await clickWidget("button", "Calibrate");
  s = await waitFor("the calibration", idleWith((s) => s.calibrated), 300_000);
  check(/^Calibration done/.test(s.status) && s.errors.length === 0, `Calibrate finishes: ${s.status}`);
  const ver = s.calibrated.ver;
  check(s.calibrated.converged && ver.collaborative.pos_rms_mm < 0.05,
    `calibrated figures: verification collaborative RMS ${ver.collaborative.pos_rms_mm.toFixed(4)} mm (nominal ${s.session.nominal.ver.collaborative.pos_rms_mm.toFixed(3)} mm)`);
  check(await widget("button", "Parameters (JSON)…").count() > 0 &&
    (await widget("button", "Parameters (JSON)…").getAttribute("aria-disabled")) !== "true",
    "the accessibility tree shows the parameter export enabled");
  metrics.stepped_run = { ...s.last_run, solver_s: s.calibrated.solver_compute_s };
  metrics.iterations = s.iterations;
  fs.writeFileSync(path.join(out, "status.json"), JSON.stringify(s, null, 2));
  fs.writeFileSync(path.join(out, "params-browser.json"), JSON.stringify(s.calibrated.params, null, 2));
  await frames(3);
  await page.screenshot({ path: path.join(out, "workbench.png") });

  // ---- exports are downloads -------------------------------------------------------------------
  const params = await download("Parameters (JSON)…");
  const parsed = JSON.parse(params.bytes.toString("utf8"));
  check(params.name === "params.json" && parsed.format === "dualcal-params/1",
    `"Parameters (JSON)…" downloads ${params.name} (${parsed.format})`);
  const urdf = await download("Calibrated URDF…");
  check(urdf.name === "calibrated.urdf" && /<robot[\s>]/.test(urdf.bytes.toString("utf8")),
    `"Calibrated URDF…" downloads ${urdf.name} (${urdf.bytes.length} bytes)`);
  const csv = await download("Configuration errors (CSV)…");
  const lines = csv.bytes.toString("utf8").trim().split("\n");
  check(csv.name === "configurations.csv" && lines[0].startsWith("id,arm,split") && lines.length === 441,
    `"Configuration errors (CSV)…" downloads ${csv.name} (${lines.length - 1} rows)`);
  const png = await download("Plots (PNG)…");
  check(png.name === "dualcal-plots.png" && png.bytes.subarray(1, 4).toString() === "PNG" && png.bytes.length > 2000,
    `"Plots (PNG)…" downloads ${png.name} (${png.bytes.length} bytes)`);
  const report = await download("Calibration report (HTML)…");
  const reportText = report.bytes.toString("utf8");
  const reportSections = (reportText.match(/<section id="/g) || []).length;
  check(report.name === "report.html" && reportSections === 10 && reportText.includes("the workbench&#39;s calibration"),
    `"Calibration report (HTML)…" downloads ${report.name} (${reportSections} sections, ${report.bytes.length} bytes)`);

  // ---- open a dataset from files picked together ------------------------------------------------
  const example = path.join(root, "assets/datasets/example");
  const chooser = page.waitForEvent("filechooser", { timeout: 20_000 });
  await clickWidget("button", "Open dataset…");
  await (await chooser).setFiles(["dataset.toml", "left.csv", "right.csv"].map((f) => path.join(example, f)));
  s = await waitFor("opening the picked files", idleWith((s) => s.session?.dataset.startsWith("/uploads/")), 60_000);
  check(s.errors.length === 0 && s.session.configurations.join("+") === "220+220",
    `"Open dataset…" opens the picked files: ${s.status}`);
  const picked = s.session.dataset;

  // ---- a .zip dropped on the canvas opens ------------------------------------------------------
  const zip = fs.readFileSync(path.join(out, "example.zip")).toString("base64");
  await page.evaluate((b64) => {
    const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const transfer = new DataTransfer();
    transfer.items.add(new File([bytes], "example.zip", { type: "application/zip" }));
    const canvas = document.getElementById("dualcal-canvas");
    for (const type of ["dragenter", "dragover", "drop"]) {
      canvas.dispatchEvent(new DragEvent(type, { dataTransfer: transfer, bubbles: true, cancelable: true, clientX: 700, clientY: 450 }));
    }
  }, zip);
  s = await waitFor("opening the dropped .zip",
    idleWith((s) => s.session?.dataset !== picked && s.session?.dataset.startsWith("/uploads/")), 60_000);
  check(s.errors.length === 0 && s.session.dataset.endsWith("/example"),
    `a dropped .zip opens: ${s.status}`);

  // ---- a URDF with a loose mesh file, picked together ---------------------------------------------
  // The built-in robot's description with its body drawn from a mesh (a tetrahedron written here).
  const urdfText = fs.readFileSync(path.join(root, "assets/irb14000.urdf"), "utf8");
  const withMesh = urdfText.replace(/(<link name="yumi_body">[\s\S]*?<geometry>)[\s\S]*?(<\/geometry>)/,
    `$1<mesh filename="package://test_description/meshes/body.stl" scale="0.001 0.001 0.001"/>$2`);
  check(withMesh !== urdfText, "the test URDF names a mesh");
  const stl = Buffer.alloc(84 + 4 * 50);
  stl.writeUInt32LE(4, 80);
  const tri = [[0, 0, 0], [100, 0, 0], [0, 100, 0], [0, 0, 100]];
  [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]].forEach((f, k) => {
    f.forEach((v, j) => tri[v].forEach((c, i) => stl.writeFloatLE(c, 84 + 50 * k + 12 + 12 * j + 4 * i)));
  });
  const urdfDir = fs.mkdtempSync(path.join(os.tmpdir(), "dualcal-urdf-"));
  fs.writeFileSync(path.join(urdfDir, "robot.urdf"), withMesh);
  fs.writeFileSync(path.join(urdfDir, "body.stl"), stl);
  const urdfChooser = page.waitForEvent("filechooser", { timeout: 20_000 });
  await clickWidget("button", "Open URDF…");
  await (await urdfChooser).setFiles([path.join(urdfDir, "robot.urdf"), path.join(urdfDir, "body.stl")]);
  s = await waitFor("opening the picked URDF",
    idleWith((s) => s.session?.robot_source?.startsWith("/uploads/")), 60_000);
  fs.rmSync(urdfDir, { recursive: true, force: true });
  check(s.errors.length === 0 && s.session.robot_warnings.length === 0 && s.session.robot_source.endsWith("/robot.urdf"),
    `"Open URDF…" opens a URDF with its loose mesh: ${s.session.robot_source}, warnings ${JSON.stringify(s.session.robot_warnings)}`);

  // ---- the import window: each arm's tracker export and joint log picked, opened in memory -------
  // The example's measurements as a SpatialAnalyzer-style export and a joint log per arm.
  const trackerDir = fs.mkdtempSync(path.join(os.tmpdir(), "dualcal-import-"));
  for (const side of ["left", "right"]) {
    const rows = fs.readFileSync(path.join(example, `${side}.csv`), "utf8").split("\n")
      .filter((l) => l && !l.startsWith("#")).slice(1).map((l) => l.split(","));
    const points = ["// exported for the browser test", "// units: mm"];
    const joints = ["id,q1,q2,q3,q4,q5,q6,q7"];
    for (const f of rows) {
      joints.push(f.slice(0, 8).join(","));
      ["a", "b", "c"].forEach((r, k) => points.push(`${f[0]}_${r} ${f.slice(8 + 3 * k, 11 + 3 * k).join(" ")}`));
    }
    fs.writeFileSync(path.join(trackerDir, `${side}-points.txt`), points.join("\n") + "\n");
    fs.writeFileSync(path.join(trackerDir, `${side}-joints.csv`), joints.join("\n") + "\n");
  }
  const beforeImport = s.session.dataset;
  await clickWidget("button", "Import…");
  for (const side of ["left", "right"]) {
    for (const [kind, file] of [["points", `${side}-points.txt`], ["joints", `${side}-joints.csv`]]) {
      const picker = page.waitForEvent("filechooser", { timeout: 20_000 });
      await clickWidget("button", `${side} ${kind}…`);
      await (await picker).setFiles([path.join(trackerDir, file)]);
      await frames(3);
    }
  }
  await clickWidget("button", "Open in the workbench");
  s = await waitFor("opening the import",
    idleWith((s) => s.session?.dataset !== beforeImport && s.session?.dataset.startsWith("/imports/")), 60_000);
  fs.rmSync(trackerDir, { recursive: true, force: true });
  check(s.errors.length === 0 && s.session.configurations.join("+") === "220+220",
    `"Import…" previews the picked tracker files and opens them: ${s.session.dataset}, ${s.status}`);

  // ---- compute alone: with an unlimited budget the run is computed in as few frames as it can ---
  await page.goto(`${base}&budget_ms=60000`, { waitUntil: "load" });
  s = await waitFor("reopening the example", idleWith((s) => s.session), 120_000);
  await clickWidget("button", "Calibrate");
  s = await waitFor("the unlimited-budget run", idleWith((s) => s.calibrated), 120_000);
  metrics.unlimited_budget_run = { ...s.last_run, solver_s: s.calibrated.solver_compute_s };
  fs.writeFileSync(path.join(out, "params-browser-unlimited.json"), JSON.stringify(s.calibrated.params, null, 2));

  // ---- live curves and Cancel: one outer iteration per frame (?budget_ms=0) ----------------------
  await page.goto(`${base}&budget_ms=0`, { waitUntil: "load" });
  s = await waitFor("reopening the example", idleWith((s) => s.session), 120_000);
  await clickWidget("button", "Calibrate");
  s = await waitFor("the run iterating", (s) => s.phase === "calibrating" && s.iterations >= 2, 60_000);
  const before = s.iterations;
  s = await waitFor("the curves moving", (s) => s.iterations > before, 60_000);
  check(s.phase === "calibrating", `the run advances frame by frame (iteration ${before} → ${s.iterations})`);
  await clickWidget("button", "Cancel");
  s = await waitFor("cancelling", idleWith(() => true), 60_000);
  check(/cancelled/.test(s.status) && s.calibrated === null, `Cancel stops the run: ${s.status}`);

  // ---- the page's own choice: WebGPU on a hardware adapter, else WebGL2 where there is WebGL2 ----------
  // On the WebGL2 run this browser has no WebGPU adapter; on the WebGPU run its adapter is
  // SwiftShader's, a fallback adapter, and it has no WebGL2 (ANGLE on Vulkan gives none here).
  await page.goto(origin, { waitUntil: "load" });
  s = await waitFor("the page's own choice", idleWith((s) => s.session), 120_000);
  const chosen = await page.evaluate(() => document.documentElement.dataset.module ?? null);
  const { adapter, webgl2 } = await page.evaluate(async () => {
    const a = navigator.gpu && (await navigator.gpu.requestAdapter());
    const gl = document.createElement("canvas").getContext("webgl2");
    gl?.getExtension("WEBGL_lose_context")?.loseContext();
    return {
      adapter: a ? (a.info?.isFallbackAdapter ?? a.isFallbackAdapter ? "fallback" : "hardware") : "none",
      webgl2: Boolean(gl),
    };
  });
  const expected = adapter === "hardware" || (!webgl2 && adapter === "fallback") ? "webgpu" : "webgl2";
  check(chosen === expected && s.errors.length === 0,
    `without ?backend= the page chooses the ${chosen} module (WebGPU adapter: ${adapter}; WebGL2: ${webgl2 ? "yes" : "no"})`);

  // ---- the same parameters as the native command line --------------------------------------------
  if (nativeParams) {
    const native = JSON.parse(fs.readFileSync(nativeParams, "utf8"));
    const browser = JSON.parse(fs.readFileSync(path.join(out, "params-browser.json"), "utf8"));
    const diffs = [];
    const walk = (a, b, where) => {
      if (typeof a === "number" && typeof b === "number") {
        const rel = a === b ? 0 : Math.abs(a - b) / Math.max(Math.abs(a), Math.abs(b));
        diffs.push({ where, native: a, browser: b, rel });
      } else if (a && b && typeof a === "object") {
        for (const k of Object.keys(a)) {
          if (k in b) walk(a[k], b[k], `${where}.${k}`);
          else diffs.push({ where: `${where}.${k}`, rel: Infinity });
        }
      }
    };
    walk(native.arms, browser.arms, "arms");
    walk(native.right_base_in_left, browser.right_base_in_left, "right_base_in_left");
    diffs.sort((x, y) => y.rel - x.rel);
    metrics.params_compared = diffs.length;
    metrics.params_identical = diffs.filter((d) => d.rel === 0).length;
    metrics.params_max_rel = diffs[0]?.rel ?? null;
    metrics.params_worst = diffs.slice(0, 3);
    check(diffs.length > 50 && diffs[0].rel <= REL_TOL,
      `browser parameters equal native: ${diffs.length} values, ${metrics.params_identical} bit-identical, largest relative difference ${diffs[0]?.rel.toExponential(2)} (${diffs[0]?.where})`);
  }
} catch (e) {
  check(false, `${e.message}`);
  await page.screenshot({ path: path.join(out, "failure.png") }).catch(() => {});
} finally {
  metrics.console_errors = consoleErrors;
  check(consoleErrors.length === 0, `no console errors${consoleErrors.length ? `: ${consoleErrors.join(" | ")}` : ""}`);
  fs.writeFileSync(path.join(out, "metrics.json"), JSON.stringify(metrics, null, 2));
  await browser.close();
  server.close();
}
console.log(`browser test: ${passed} passed, ${failures.length} failed`);
process.exit(failures.length ? 1 : 0);
