// What the browser tests share: the static server of the site and headless Chromium on a software
// renderer for one of the two modules' backends.
import { chromium } from "playwright-core";
import http from "node:http";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";

const types = { ".html": "text/html", ".js": "text/javascript", ".wasm": "application/wasm" };

// Serve `site` on 127.0.0.1 (a free port), uncached; `served()` counts the bytes sent (the page's
// load size). Resolves to { origin, served, close }.
export async function serveSite(site) {
  let servedBytes = 0;
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, "http://127.0.0.1");
    const rel = url.pathname === "/" ? "index.html" : decodeURIComponent(url.pathname).replace(/^\/+/, "");
    const file = path.join(site, rel);
    if (!file.startsWith(site) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      res.writeHead(404).end();
      return;
    }
    const body = fs.readFileSync(file);
    servedBytes += body.length;
    res.writeHead(200, {
      "content-type": types[path.extname(file)] ?? "application/octet-stream",
      "cache-control": "no-store",
    });
    res.end(body);
  });
  await new Promise((resolve) => server.listen(0, "127.0.0.1", resolve));
  return {
    origin: `http://127.0.0.1:${server.address().port}/`,
    served: () => servedBytes,
    close: () => server.close(),
  };
}

// Chromium headless on software renderers (SwiftShader), off the network, with a fresh profile.
// WebGL2: ANGLE on SwiftShader's GL. WebGPU: Dawn on SwiftShader's Vulkan, with Skia and ANGLE on
// Vulkan too, so that the compositor shares the WebGPU canvas's images (under the WebGL2 flags the
// page gets an adapter but its canvas is never presented: "Could not find SharedImageBackingFactory
// … WebGPUSwapBufferProvider" in the GPU process's log). Resolves to { context, page, close }.
export async function launchChromium(backend, { width = 1400, height = 900, acceptDownloads = false } = {}) {
  const rendererArgs = {
    webgl2: ["--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
    webgpu: ["--enable-unsafe-webgpu", "--enable-features=Vulkan", "--use-vulkan=swiftshader", "--use-angle=vulkan"],
  }[backend];
  if (!rendererArgs) throw new Error(`backend ${backend}: expected webgl2 or webgpu`);
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "dualcal-chromium-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
    headless: true,
    viewport: { width, height },
    acceptDownloads,
    args: [
      "--no-sandbox",
      ...rendererArgs,
      "--disable-gpu-sandbox",
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-default-apps",
      "--disable-domain-reliability",
      "--disable-sync",
      "--no-first-run",
      "--no-default-browser-check",
      "--disable-quic",
      "--proxy-server=127.0.0.1:9",
      "--proxy-bypass-list=127.0.0.1",
    ],
  });
  const page = context.pages()[0] ?? (await context.newPage());
  return {
    context,
    page,
    close: async () => {
      await context.close();
      fs.rmSync(profile, { recursive: true, force: true });
    },
  };
}
