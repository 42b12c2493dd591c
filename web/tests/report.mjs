// The browser figures of docs/performance.md from what `tools/web.sh measure` left in target/web-test:
// build.json (wasm size), metrics.json (the browser test), native-cli-secs.txt (the release CLI's
// solver time, 5 runs), native-in-frames.json (examples/calibrate_in_frames, release).
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

const dir = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../../target/web-test");
const read = (f) => JSON.parse(fs.readFileSync(path.join(dir, f), "utf8"));
const build = read("build.json");
const m = read("metrics.json");
const nativeFrames = read("native-in-frames.json");
const cli = fs.readFileSync(path.join(dir, "native-cli-secs.txt"), "utf8").trim().split(/\s+/).map(Number).sort((a, b) => a - b);
const median = (xs) => xs[Math.floor(xs.length / 2)];
const kib = (b) => `${(b / 1024).toFixed(0)} KiB`;
const s = (x) => `${x.toFixed(3)} s`;
const browserCompute = m.unlimited_budget_run.compute_s;
const nativeCompute = nativeFrames.median_compute_s;
console.log(`| figure | browser (release wasm, headless Chromium, SwiftShader WebGL2) | native (release) |
|---|---|---|
| wasm module | ${kib(build.wasm_bytes)} raw, ${kib(build.wasm_gzip_bytes)} gzip -9 | — |
| page load (html + js + wasm served) | ${(m.load_bytes / 1e6).toFixed(1)} MB | — |
| time to first frame (navigation start → first frame) | ${(m.first_frame_ms / 1000).toFixed(2)} s | — |
| calibration of the example, compute (solver + figures, unlimited budget) | ${s(browserCompute)} in ${m.unlimited_budget_run.frames} frames | ${s(nativeCompute)} (same work stepped in frames, median of ${nativeFrames.compute_s.length}) — browser/native ${(browserCompute / nativeCompute).toFixed(2)}× |
| solver alone (its steps' time) | ${s(m.unlimited_budget_run.solver_s)} | ${s(nativeFrames.median_solver_s)} (same task); CLI \`total time\` ${s(median(cli))} (median of ${cli.length}) — browser/native ${(m.unlimited_budget_run.solver_s / nativeFrames.median_solver_s).toFixed(2)}× |
| calibration with the adaptive budget: wall / compute | ${s(m.stepped_run.wall_s)} / ${s(m.stepped_run.compute_s)} in ${m.stepped_run.frames} frames, longest slice ${m.stepped_run.longest_slice_ms.toFixed(0)} ms | — |
| parameters vs native CLI | ${m.params_compared} values, ${m.params_identical} bit-identical, largest relative difference ${m.params_max_rel.toExponential(2)} | — |
| renderer | ${m.renderer} | — |`);
