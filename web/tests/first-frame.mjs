// The time to the workbench's first frame, over several page loads (each in a fresh browser profile,
// so nothing is cached): its median and range per module, and where it goes — the page's own
// performance marks (web/index.html: the module's response, its JavaScript glue loaded, the module
// compiled, instantiated and started; src/app/web.rs: wgpu's adapter and device and egui's painter
// ready, the app created) and the app's first frame (`data-first-frame-ms`).
//
//   node web/tests/first-frame.mjs [--loads N] [--backend webgl2|webgpu|both]   (tools/web.sh first-frame)
//
// Reads the site in target/web (DUALCAL_WEB_SITE); prints one line per load and a summary per module.
import path from "node:path";
import { fileURLToPath } from "node:url";
import { launchChromium, serveSite } from "./harness.mjs";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../..");
const site = process.env.DUALCAL_WEB_SITE ?? path.join(root, "target/web");
const args = process.argv.slice(2);
const option = (name, fallback) => (args.includes(name) ? args[args.indexOf(name) + 1] : fallback);
const loads = Number(option("--loads", "7"));
const which = option("--backend", "both");
const backends = which === "both" ? ["webgl2", "webgpu"] : [which];
if (!(loads >= 1) || !backends.every((b) => ["webgl2", "webgpu"].includes(b))) {
  console.error("first-frame: --loads N (≥ 1), --backend webgl2|webgpu|both");
  process.exit(2);
}

const server = await serveSite(site);
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
const summary = [];
for (const backend of backends) {
  const rows = [];
  for (let i = 0; i < loads; i++) {
    const browser = await launchChromium(backend);
    try {
      await browser.page.goto(`${server.origin}?backend=${backend}`, { waitUntil: "load" });
      await browser.page.waitForFunction(
        () => document.getElementById("dualcal-status").getAttribute("data-first-frame-ms"), null, { timeout: 60_000 });
      const row = await browser.page.evaluate(() => {
        const mark = (name) => performance.getEntriesByName(name)[0]?.startTime ?? NaN;
        return {
          response: mark("dualcal:module-response"),
          glue: mark("dualcal:glue-loaded"),
          started: mark("dualcal:module-started"),
          renderer: mark("dualcal:renderer-ready"),
          app: mark("dualcal:app-created"),
          first_frame: Number(document.getElementById("dualcal-status").getAttribute("data-first-frame-ms")),
        };
      });
      rows.push(row);
      console.log(`${backend} load ${i + 1}: module response ${row.response.toFixed(0)} ms, glue ${row.glue.toFixed(0)} ms, ` +
        `module compiled and started ${row.started.toFixed(0)} ms, renderer ready ${row.renderer.toFixed(0)} ms, ` +
        `app created ${row.app.toFixed(0)} ms, first frame ${row.first_frame} ms`);
    } finally {
      await browser.close();
    }
  }
  const ff = rows.map((r) => r.first_frame);
  summary.push(`${backend}: first frame median ${median(ff)} ms (${Math.min(...ff)}–${Math.max(...ff)}, ${loads} loads); ` +
    `medians: module compiled and started ${median(rows.map((r) => r.started)).toFixed(0)} ms, ` +
    `renderer ready ${median(rows.map((r) => r.renderer)).toFixed(0)} ms, app created ${median(rows.map((r) => r.app)).toFixed(0)} ms`);
}
server.close();
for (const line of summary) console.log(line);
