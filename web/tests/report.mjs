// The browser figures of docs/performance.md from what `tools/web.sh measure` left in target/web-test:
// build.json (both modules' sizes), metrics.json and webgpu/metrics.json (the browser test on each
// module), native-cli-secs.txt (the release command line's solver time, 5 runs).
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

const dir = process.env.DUALCAL_WEB_TEST_OUT ?? path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../../target/web-test");
const read = (f) => JSON.parse(fs.readFileSync(path.join(dir, f), "utf8"));
const build = read("build.json");
const cli = fs.readFileSync(path.join(dir, "native-cli-secs.txt"), "utf8").trim().split(/\s+/).map(Number).sort((a, b) => a - b);
const native = cli[Math.floor(cli.length / 2)];
const kib = (b) => `${(b / 1024).toFixed(0)} KiB`;
const s = (x) => `${x.toFixed(3)} s`;
for (const module of build.modules) {
  const m = read(module.backend === "webgl2" ? "metrics.json" : `${module.backend}/metrics.json`);
  const one = m.unlimited_budget_run;
  const stepped = m.stepped_run;
  console.log(`
| | browser (release wasm, headless Chromium, SwiftShader ${module.backend === "webgpu" ? "WebGPU (Vulkan)" : "WebGL2"}) | native (release) |
|---|---|---|
| wasm module \`${module.file}\` | ${kib(module.wasm_bytes)} raw, ${kib(module.wasm_gzip_bytes)} gzip -9 (${module.wasm_bytes} / ${module.wasm_gzip_bytes} bytes) | — |
| page load (html + js + wasm served) | ${(m.load_bytes / 1e6).toFixed(2)} MB | — |
| time to first frame | ${(m.first_frame_ms / 1000).toFixed(2)} s | — |
| the example's calibration, solver | ${s(one.solver_s)} (unlimited budget), ${s(stepped.solver_s)} (adaptive budget) | ${s(native)} (\`dualcal calibrate\` \`total time\`, median of ${cli.join(", ")}) |
| browser / native, solver | ${(one.solver_s / native).toFixed(1)}× and ${(stepped.solver_s / native).toFixed(1)}× | |
| + figures (live views, final evaluation) | compute ${s(one.compute_s)} in ${one.frames} frames (unlimited budget) | — |
| Calibrate → done with the adaptive budget: wall / compute | ${s(stepped.wall_s)} / ${s(stepped.compute_s)} in ${stepped.frames} frames, longest slice ${stepped.longest_slice_ms.toFixed(0)} ms | — |
| parameters vs native | ${m.params_compared} values, ${m.params_identical} bit-identical, largest relative difference ${m.params_max_rel.toExponential(2)} | |`);
}
