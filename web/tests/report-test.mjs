// The calibration report (`dualcal report … --out report.html`) in a real browser: Debian's
// Chromium, headless, driven by playwright-core, the file opened from disk with the network off.
//
//   node web/tests/report-test.mjs path/to/report.html      (tools/web.sh test runs it)
//
// Checks: no console error and no failed request (the file is self-contained: nothing is fetched);
// every section (#dataset … #warnings) exists, has a heading and is visible once scrolled to; the
// figures are inline SVG that the browser laid out with a size; the accuracy tables carry numbers.
// Writes a full-page screenshot to target/web-test/report.png, the first screen to report-top.png and
// the figures section to report-figures.png (DUALCAL_WEB_TEST_OUT overrides the directory).
import { chromium } from "playwright-core";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../..");
const out = process.env.DUALCAL_WEB_TEST_OUT ?? path.join(root, "target/web-test");
const chromiumPath = process.env.CHROMIUM ?? "/usr/bin/chromium";
const SECTIONS = [
  "dataset",
  "robot",
  "method",
  "identifiability",
  "parameters",
  "accuracy",
  "figures",
  "worst",
  "screening",
  "warnings",
];

const file = process.argv[2];
if (!file || !fs.existsSync(file)) {
  console.error("usage: node web/tests/report-test.mjs REPORT.html");
  process.exit(2);
}
fs.mkdirSync(out, { recursive: true });
let passed = 0;
const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? "ok  " : "FAIL"} ${what}`);
  if (ok) passed++;
  else failures.push(what);
};

const profile = fs.mkdtempSync(path.join(os.tmpdir(), "dualcal-report-"));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: chromiumPath,
  headless: true,
  viewport: { width: 1280, height: 900 },
  args: [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-default-apps",
    "--disable-sync",
    "--no-first-run",
    "--no-default-browser-check",
    // Off the network: a report that fetched anything would show a failed request.
    "--proxy-server=127.0.0.1:9",
  ],
});
try {
  const page = context.pages()[0] ?? (await context.newPage());
  const consoleErrors = [];
  const requests = [];
  page.on("console", (m) => {
    if (m.type() === "error") consoleErrors.push(m.text());
  });
  page.on("pageerror", (e) => consoleErrors.push(`page error: ${e.message}`));
  page.on("request", (r) => {
    if (!r.url().startsWith("file:")) requests.push(r.url());
  });
  page.on("requestfailed", (r) => consoleErrors.push(`request failed: ${r.url()}`));

  const url = pathToFileURL(path.resolve(file)).href;
  const response = await page.goto(url, { waitUntil: "load" });
  check(response === null || response.ok(), `the report opens (${url})`);
  const title = await page.title();
  check(title.startsWith("Calibration report"), `title: ${title}`);

  for (const id of SECTIONS) {
    const section = page.locator(`section#${id}`);
    const count = await section.count();
    check(count === 1, `section #${id} exists once (${count})`);
    if (count !== 1) continue;
    const heading = (await section.locator("h2").first().textContent())?.trim() ?? "";
    check(heading.length > 0, `section #${id} has a heading: ${heading}`);
    await section.scrollIntoViewIfNeeded();
    check(await section.isVisible(), `section #${id} is visible`);
    const box = await section.boundingBox();
    check(box !== null && box.height > 20, `section #${id} has a size (${box?.height?.toFixed(0)} px)`);
  }

  const svgs = page.locator("#figures svg");
  const nSvg = await svgs.count();
  check(nSvg >= 4, `the figures are inline SVG (${nSvg})`);
  let sized = 0;
  for (let k = 0; k < nSvg; k++) {
    const b = await svgs.nth(k).boundingBox();
    if (b && b.width > 100 && b.height > 80) sized++;
  }
  check(nSvg > 0 && sized === nSvg, `every figure is laid out with a size (${sized} of ${nSvg})`);

  const values = await page.locator("#accuracy td[data-value]").count();
  check(values > 10, `the accuracy tables carry numbers (${values} cells)`);
  const sigmas = await page.locator("#parameters td[data-param]").count();
  check(sigmas > 0, `the parameter tables list the parameters (${sigmas})`);

  await page.evaluate(() => window.scrollTo(0, 0));
  await page.screenshot({ path: path.join(out, "report.png"), fullPage: true });
  // The top of the page (summary, dataset) and the figures alone, for the docs.
  await page.screenshot({ path: path.join(out, "report-top.png") });
  await page.locator("section#figures").screenshot({ path: path.join(out, "report-figures.png") });
  check(requests.length === 0, `nothing fetched (${requests.join(", ") || "no request"})`);
  check(consoleErrors.length === 0, `no console errors${consoleErrors.length ? `: ${consoleErrors.join(" | ")}` : ""}`);
} finally {
  await context.close();
  fs.rmSync(profile, { recursive: true, force: true });
}

console.log(`${passed} passed, ${failures.length} failed; screenshot ${path.join(out, "report.png")}`);
if (failures.length > 0) {
  for (const f of failures) console.log(`FAIL ${f}`);
  process.exit(1);
}
