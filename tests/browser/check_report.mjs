// SPDX-License-Identifier: Apache-2.0
// Browser test of an `envpis compare` report: opens DIR/index.html from the file system in headless
// Chromium (Debian's /usr/bin/chromium, driven by playwright-core) and checks that
//   - the page loads with no console error, no uncaught exception and no failed request,
//   - it requests nothing but file: URLs (self-contained, works offline),
//   - every <img> is loaded (complete, naturalWidth > 0): the reference, every strategy's image and
//     error map at equal spp and equal time, and every plot listed in metrics.json,
//   - every strategy of metrics.json has its image, and every plot is shown,
//   - the linked zoom works: hovering over one image moves the marker in all of them and updates the
//     insets.
//   - the summary tables show the tail (max rel. sq. err., pixels > 10x off) next to relMSE, with the
//     median over seeds and its [min, max] spread when metrics.json has several seeds, and the per-object
//     tail tables have a row per object.
//   - when metrics.json has an "analysis", its table shows a row per analyzed object with a number in
//     every V cell (one per analyzed strategy, and product*) and in every decomposition column.
//
//   node tests/browser/check_report.mjs DIR [--screenshot FILE] [--allow-no-plots]
//
// Environment: CHROMIUM overrides /usr/bin/chromium. Exit status 0 = pass, 1 = fail, 2 = usage.
import { existsSync, readFileSync } from "node:fs";
import path from "node:path";
import { pathToFileURL } from "node:url";
import { chromium } from "playwright-core";

const args = process.argv.slice(2);
let dir = null, screenshot = null, allowNoPlots = false;
for (let i = 0; i < args.length; ++i) {
  if (args[i] === "--screenshot") screenshot = args[++i];
  else if (args[i] === "--allow-no-plots") allowNoPlots = true;
  else if (!dir) dir = args[i];
  else { console.log(`check_report: unexpected argument '${args[i]}'`); process.exit(2); }
}
if (!dir) { console.log("usage: node check_report.mjs DIR [--screenshot FILE] [--allow-no-plots]"); process.exit(2); }
const indexPath = path.resolve(dir, "index.html");
const metricsPath = path.resolve(dir, "metrics.json");
for (const f of [indexPath, metricsPath]) if (!existsSync(f)) { console.log(`check_report: missing ${f}`); process.exit(1); }
const metrics = JSON.parse(readFileSync(metricsPath, "utf8"));
const failures = [];
const fail = (msg) => failures.push(msg);

// The page source itself must not reference the network.
const html = readFileSync(indexPath, "utf8");
for (const m of html.matchAll(/(?:src|href)\s*=\s*["']?\s*(https?:|\/\/)/gi)) fail(`index.html references an external URL: ${m[0]}`);
if (/url\(\s*["']?(https?:|\/\/)/i.test(html)) fail("index.html has a CSS url() to an external address");

const executablePath = process.env.CHROMIUM || "/usr/bin/chromium";
const browser = await chromium.launch({
  executablePath,
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", "--no-first-run"],  // playwright gives every launch a fresh temporary profile
}).catch((e) => { console.log(`check_report: cannot start ${executablePath}: ${e.message}`); process.exit(1); });

try {
  const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
  page.on("console", (msg) => { if (msg.type() === "error") fail(`console error: ${msg.text()}`); });
  page.on("pageerror", (err) => fail(`uncaught exception: ${err.message}`));
  page.on("requestfailed", (req) => fail(`request failed: ${req.url()} (${req.failure()?.errorText})`));
  page.on("request", (req) => {
    const u = req.url();
    if (!u.startsWith("file:") && !u.startsWith("data:")) fail(`request to a non-file URL: ${u}`);
  });

  await page.goto(pathToFileURL(indexPath).href, { waitUntil: "load", timeout: 30000 });
  // Images appended by the page's script after parsing: wait until each has finished loading or failed.
  await page.waitForFunction(() => Array.from(document.images).every((i) => i.complete), null, { timeout: 15000 })
    .catch(() => fail("some images never finished loading"));

  const imgs = await page.evaluate(() => Array.from(document.images).map((i) => ({
    src: i.getAttribute("src"), complete: i.complete, w: i.naturalWidth, h: i.naturalHeight })));
  if (imgs.length === 0) fail("the page has no images");
  for (const i of imgs) if (!i.complete || !(i.w > 0) || !(i.h > 0)) fail(`image not rendered: ${i.src} (${i.w}x${i.h})`);
  const srcs = new Set(imgs.map((i) => i.src));

  // Every image the metrics name must be on the page.
  const expected = [metrics.reference.png];
  for (const key of ["equal_spp", "equal_time"]) {
    if (!metrics[key]) continue;
    for (const s of metrics[key].strategies) expected.push(s.images.png, s.images.error_png);
  }
  if (metrics.plots && metrics.plots.figures) {
    if (metrics.plots.figures.length === 0) fail("metrics.json lists no plots");
    for (const f of metrics.plots.figures) expected.push(f.file);
  } else if (!allowNoPlots) {
    fail(`no plots: ${metrics.plots_unavailable || "metrics.json has no plots"}`);
  }
  for (const e of expected) if (!srcs.has(e)) fail(`image missing from the page: ${e}`);

  // Plots are <figure> elements with a rendered image.
  const figures = await page.evaluate(() => Array.from(document.querySelectorAll(".plots figure img")).map((i) => i.naturalWidth));
  const nplots = metrics.plots && metrics.plots.figures ? metrics.plots.figures.length : 0;
  if (figures.length !== nplots) fail(`expected ${nplots} plots on the page, found ${figures.length}`);

  // Linked zoom: hover near the right end of the reference image; every marker moves there.
  const target = page.locator(".imgwrap").first();
  await target.scrollIntoViewIfNeeded().catch(() => {});
  const box = await target.boundingBox();
  if (!box) {
    fail("no zoomable image");
  } else {
    await target.hover({ position: { x: box.width * 0.85, y: box.height * 0.5 } });
    const state = await page.evaluate(() => ({
      lefts: Array.from(document.querySelectorAll(".marker")).map((m) => parseFloat(m.style.left)),
      insets: Array.from(document.querySelectorAll(".inset")).map((d) => d.style.backgroundPosition),
    }));
    if (state.lefts.length < 2) fail(`expected a marker per image, found ${state.lefts.length}`);
    const first = state.lefts[0];
    if (!(first > 50)) fail(`zoom marker did not follow the pointer (left ${first}%)`);
    if (state.lefts.some((l) => Math.abs(l - first) > 1e-6)) fail("zoom markers are not linked (different positions)");
    if (state.insets.length === 0 || state.insets.some((p) => !p)) fail("zoom insets are not positioned");
  }

  // The numbers are on the page.
  const text = await page.evaluate(() => document.body.innerText);
  for (const s of metrics.equal_spp.strategies) if (!text.includes(s.strategy)) fail(`strategy ${s.strategy} not shown`);
  if (metrics.overhead && !text.includes("Overhead")) fail("overhead ratio not shown");

  // The summary tables show the tail next to relMSE, and with several seeds the median and its spread;
  // one row per strategy, a number in every tail cell.
  const nseeds = (metrics.seeds || []).length || 1;
  const tables = await page.evaluate(() => Array.from(document.querySelectorAll("table.summary")).map((t) =>
    Array.from(t.querySelectorAll("tr")).map((r) => Array.from(r.children).map((c) => c.textContent))));
  const blocks = ["equal_spp", "equal_time"].filter((k) => metrics[k]);
  if (tables.length !== blocks.length) fail(`expected ${blocks.length} summary tables, found ${tables.length}`);
  const wanted = ["max rel. sq. err.", "px > 10\u00d7 off"].concat(
    nseeds > 1 ? ["median relMSE", "[min, max]"] : ["relMSE"]);
  tables.forEach((rows, i) => {
    const head = rows[0] || [];
    for (const w of wanted) if (!head.includes(w)) fail(`summary table ${i + 1} lacks the column '${w}'`);
    const strategies = metrics[blocks[i]].strategies;
    if (rows.length !== strategies.length + 1) fail(`summary table ${i + 1}: ${rows.length - 1} rows for ${strategies.length} strategies`);
    for (const w of ["max rel. sq. err.", "px > 10\u00d7 off"]) {
      const col = head.indexOf(w);
      for (const r of rows.slice(1))
        if (col >= 0 && !/^[0-9]/.test(r[col] || "")) fail(`summary table ${i + 1}, ${r[0]}: '${w}' is '${r[col]}'`);
    }
  });
  const tailRows = await page.evaluate(() => Array.from(document.querySelectorAll("table.tail")).map((t) => t.rows.length));
  if ((metrics.regions || []).length && (tailRows.length !== blocks.length || tailRows.some((n) => n !== metrics.regions.length + 2)))
    fail(`expected ${blocks.length} per-object tail tables of ${metrics.regions.length} objects, found rows ${JSON.stringify(tailRows)}`);

  // The exact variance analysis: one row per object (after the two header rows), a number in every cell
  // of the strategies, product* and the decomposition (a ratio may be "\u2013" only when its value is null).
  if (metrics.analysis) {
    const A = metrics.analysis;
    const rows = await page.evaluate(() => Array.from(document.querySelectorAll("table.analysis tr")).map((r) =>
      Array.from(r.children).map((c) => c.textContent)));
    if (rows.length !== A.objects.length + 2) fail(`analysis table: ${rows.length - 2} rows for ${A.objects.length} objects`);
    const head = rows[1] || [];
    const columns = A.strategies.concat(["product*", "env / product", "product / exact-12", "exact-12 / exact-48", "mis / product"]);
    if (JSON.stringify(head) !== JSON.stringify(columns)) fail(`analysis table columns ${JSON.stringify(head)}, expected ${JSON.stringify(columns)}`);
    const keys = ["env_light/product_light", "product_light/exact-12", "exact-12/exact-48", "mis/product"];
    A.objects.forEach((o, i) => {
      const cells = (rows[i + 2] || []).slice(2);
      const values = A.strategies.map((s) => o.v[s]).concat([o.v_product_limit], keys.map((k) => o.ratios[k]));
      cells.forEach((c, j) => {
        if (values[j] === null ? c !== "\u2013" : !/^[0-9]/.test(c)) fail(`analysis table, ${o.name}, column ${columns[j]}: '${c}'`);
      });
      if (cells.length !== columns.length) fail(`analysis table, ${o.name}: ${cells.length} cells for ${columns.length} columns`);
    });
  } else if (!metrics.analysis_unavailable && !("analysis" in metrics)) {
    fail("metrics.json has no \"analysis\" key");
  }

  if (screenshot) await page.screenshot({ path: screenshot, fullPage: true });
  console.log(`check_report: ${imgs.length} images, ${figures.length} plots, ${expected.length} expected images checked`);
} finally {
  await browser.close();
}

if (failures.length) {
  for (const f of failures) console.log(`check_report: FAIL ${f}`);
  process.exit(1);
}
console.log("check_report: PASS");
