// SPDX-License-Identifier: Apache-2.0
// envpis compare report: builds the page from the metrics embedded in index.html (the same data as
// metrics.json). Inlined by `envpis compare`; no external resource. Linked zoom: hovering over any image
// moves one square region in every image of the page, shown magnified in the inset strips; a click
// pins the region (click again to follow the pointer), the zoom buttons change the magnification.
"use strict";
(function () {
  const M = JSON.parse(document.getElementById("metrics").textContent);
  const root = document.getElementById("report");
  const banner = document.getElementById("banner");
  const W = M.width, H = M.height;

  // ------------------------------------------------------------------ helpers
  function el(tag, attrs, children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "class") e.className = v;
      else if (k === "text") e.textContent = v;
      else if (k === "html") e.innerHTML = v;
      else e.setAttribute(k, v);
    }
    for (const c of children || []) if (c) e.appendChild(typeof c === "string" ? document.createTextNode(c) : c);
    return e;
  }
  function fmt(x, digits) {
    if (x === null || x === undefined || !isFinite(x)) return "\u2013";
    const a = Math.abs(x);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return x.toExponential((digits || 3) - 1);
    return x.toPrecision(digits || 3);
  }
  function ratio(a, b) { return a > 0 && b > 0 ? a / b : NaN; }
  function fmtCount(x) { return x === null || x === undefined ? "\u2013" : Number.isInteger(x) ? String(x) : x.toFixed(1); }
  // With --seeds K > 1 relmse, efficiency and the tail are medians over K renders (metrics.json: seeds).
  const K = (M.seeds || []).length || 1;
  const seedsNote = K > 1 ? `relMSE, efficiency, the ratios and the tail are medians over ${K} seeds ` +
    `(${M.seeds[0]}\u2013${M.seeds[K - 1]}); [min, max]: the spread of relMSE over the seeds, (worst \u2026): the worst ` +
    `seed; the images, \u00b1 s.e., mean and timing are seed ${M.seed}'s. ` : "";
  function spread(x) { return K > 1 && x.relmse_min !== undefined ? `[${fmt(x.relmse_min, 3)}, ${fmt(x.relmse_max, 3)}]` : ""; }
  function withWorst(median, worst, f) { return K > 1 && worst !== undefined ? `${f(median)} (worst ${f(worst)})` : f(median); }
  function tailCells(x) {
    return [el("td", { text: withWorst(x.max_rel_sq_error, x.max_rel_sq_error_worst, (v) => fmt(v, 3)) }),
      el("td", { class: x.pixels_over_10x_worst || x.pixels_over_10x ? "worse" : "",
        text: withWorst(x.pixels_over_10x, x.pixels_over_10x_worst, fmtCount) })];
  }
  function regionLabel(name) { return name.startsWith("conductor-") ? "GGX " + name.slice(10) : name; }
  const brokenImages = [];
  function showBroken() {
    banner.innerHTML = "";
    if (M.plots_unavailable)
      banner.appendChild(el("p", { class: "warn", text: "Plots are unavailable: " + M.plots_unavailable + "." }));
    if (brokenImages.length)
      banner.appendChild(el("p", { class: "warn", text: "Images that failed to load: " + brokenImages.join(", ") }));
  }
  function image(src, alt) {
    const img = el("img", { src: src, alt: alt, width: String(W), height: String(H) });
    img.addEventListener("error", () => { brokenImages.push(src); showBroken(); });
    return img;
  }

  // ------------------------------------------------------------------ header
  const ref = M.reference;
  document.getElementById("subtitle").textContent =
    `${M.scene}, ${M.width}\u00d7${M.height}, environment ${M.environment}, ${M.integrator} lighting` +
    (M.max_depth ? ` (max depth ${M.max_depth})` : "") +
    `, ${M.heuristic} heuristic, ${M.threads} threads, ${M.date}. Reference: ${ref.strategy} at ${ref.spp} spp ` +
    `(seed ${ref.seed}, independent of the measured images${ref.cached ? ", cached" : ""}).`;
  showBroken();

  // ------------------------------------------------------------------ summary tables
  function summaryTable(block, title, note) {
    const sec = el("section", {}, [el("h2", { text: title })]);
    if (note) sec.appendChild(el("p", { class: "note", text: note }));
    const byName = Object.fromEntries(block.strategies.map((s) => [s.strategy, s]));
    const mis = byName["mis"], prod = byName["product"];
    const head = ["strategy", "spp", "seconds", K > 1 ? "median relMSE" : "relMSE"]
      .concat(K > 1 ? ["[min, max]"] : [])
      .concat(["\u00b1 s.e.", "efficiency", "mis / this", "this / product", "max rel. sq. err.", "px > 10\u00d7 off", "mean", "NaN px"]);
    const t = el("table", { class: "summary" }, [el("tr", {}, head.map((h) => el("th", { text: h })))]);
    const best = Math.min(...block.strategies.map((s) => s.relmse));
    for (const s of block.strategies) {
      t.appendChild(el("tr", {}, [
        el("td", { text: s.strategy }), el("td", { text: String(s.spp) }), el("td", { text: fmt(s.seconds, 3) }),
        el("td", { class: s.relmse === best ? "best" : "", text: fmt(s.relmse, 4) }),
        K > 1 ? el("td", { text: spread(s) }) : null,
        el("td", { text: s.relmse_stderr ? (100 * s.relmse_stderr / (s.relmse_seeds ? s.relmse_seeds[0] : s.relmse)).toFixed(1) + "%" : "\u2013" }),
        el("td", { text: fmt(s.efficiency, 4) }),
        el("td", { text: mis ? fmt(ratio(mis.relmse, s.relmse), 3) : "\u2013" }),
        el("td", { text: prod ? fmt(ratio(s.relmse, prod.relmse), 3) : "\u2013" }),
        ...tailCells(s),
        el("td", { text: fmt(s.mean, 4) }),
        el("td", { class: s.nan_count ? "worse" : "", text: String(s.nan_count) }),
      ]));
    }
    sec.appendChild(t);
    return sec;
  }
  function regionTable(block, title) {
    const regions = M.regions;
    const sec = el("section", {}, [el("h3", { text: title })]);
    const prod = block.strategies.find((s) => s.strategy === "product");
    const head = ["object"].concat(block.strategies.map((s) => s.strategy + " relMSE"));
    const others = block.strategies.filter((s) => s.strategy !== "product");
    if (prod) for (const s of others) head.push(s.strategy + " / product");
    const t = el("table", {}, [el("tr", {}, head.map((h) => el("th", { text: h })))]);
    for (const r of regions) {
      const vals = block.strategies.map((s) => (s.regions.find((x) => x.id === r.id) || {}).relmse);
      const best = Math.min(...vals.filter((v) => v !== null && v !== undefined));
      const row = [el("td", { text: regionLabel(r.name) })];
      block.strategies.forEach((s, i) => {
        const x = s.regions.find((y) => y.id === r.id) || {};
        row.push(el("td", { class: vals[i] === best ? "best" : "", text: fmt(vals[i], 3) + (K > 1 ? " " + spread(x) : "") }));
      });
      if (prod) {
        const p = (prod.regions.find((x) => x.id === r.id) || {}).relmse;
        for (const s of others) {
          const q = ratio((s.regions.find((x) => x.id === r.id) || {}).relmse, p);
          row.push(el("td", { class: q < 1 ? "worse" : "", text: fmt(q, 3) }));
        }
      }
      t.appendChild(el("tr", {}, row));
    }
    sec.appendChild(t);
    return sec;
  }
  function tailTable(block, title) {
    const sec = el("section", {}, [el("h3", { text: title })]);
    const head = [el("th", { text: "object", rowspan: "2" })].concat(
      block.strategies.map((s) => el("th", { text: s.strategy, colspan: "2", style: "text-align:center" })));
    const sub = [];
    for (const s of block.strategies) sub.push(el("th", { text: "max rel. sq. err." }), el("th", { text: "px > 10\u00d7 off" }));
    const t = el("table", { class: "tail" }, [el("tr", {}, head), el("tr", {}, sub)]);
    for (const r of M.regions) {
      const row = [el("td", { text: regionLabel(r.name) })];
      for (const s of block.strategies) row.push(...tailCells(s.regions.find((x) => x.id === r.id) || {}));
      t.appendChild(el("tr", {}, row));
    }
    sec.appendChild(t);
    return sec;
  }
  function biasTable(block) {
    const sec = el("section", {}, [el("h3", { text: "Bias check: z-scores of each object's mean against the reference" })]);
    sec.appendChild(el("p", { class: "note", text:
      "z = (mean \u2212 reference mean) / sqrt(var + reference var) per object, from the renderer's per-pixel " +
      "variance. An unbiased strategy gives |z| of a few at most; |z| > 5 is flagged." }));
    const head = ["object"].concat(block.strategies.map((s) => s.strategy));
    const t = el("table", {}, [el("tr", {}, head.map((h) => el("th", { text: h })))]);
    for (const r of M.regions) {
      const row = [el("td", { text: regionLabel(r.name) })];
      for (const s of block.strategies) {
        const z = (s.regions.find((x) => x.id === r.id) || {}).z;
        row.push(el("td", { class: z !== null && Math.abs(z) > 5 ? "worse" : "", text: fmt(z, 2) }));
      }
      t.appendChild(el("tr", {}, row));
    }
    sec.appendChild(t);
    return sec;
  }

  root.appendChild(summaryTable(M.equal_spp, `Equal samples: ${M.equal_spp.spp} spp`,
    "Seconds: wall time of the sampling loop, minimum over the timing repeats. \u00b1 s.e.: standard error of " +
    "relMSE from the spread of its per-pixel terms (rare fireflies that did not occur are not in it). Ratios above 1 in " +
    "\u201cmis / this\u201d mean less error than mis. The tail: max rel. sq. err. is the largest per-pixel relative " +
    "squared error (mean over channels of (I \u2212 R)\u00b2 / (R\u00b2 + 0.01)); px > 10\u00d7 off counts the pixels where it " +
    "exceeds 100. " + seedsNote));
  if (M.overhead) {
    root.appendChild(el("p", { html:
      `<b>Overhead</b> time(product) / time(mis) at ${M.overhead.spp} spp, ${M.overhead.threads} threads: ` +
      `<b>${fmt(M.overhead.ratio, 3)}</b> (${fmt(M.overhead.product_seconds, 3)} s / ${fmt(M.overhead.mis_seconds, 3)} s wall); ` +
      `in process CPU time ${fmt(M.overhead.ratio_cpu, 3)} (less sensitive to other processes on the machine).` }));
  }
  if (M.equal_time) {
    root.appendChild(summaryTable(M.equal_time, `Equal time: ${fmt(M.equal_time.budget_seconds, 3)} s of sampling each`,
      "Each strategy's spp is the budget divided by its seconds per sample at equal spp (its calibration)."));
  }
  // ------------------------------------------------------------------ plots
  const ps = el("section", {}, [el("h2", { text: "Plots" })]);
  if (M.plots && M.plots.figures && M.plots.figures.length) {
    const g = el("div", { class: "plots" });
    for (const f of M.plots.figures) {
      const img = el("img", { src: f.file, alt: f.title });
      img.addEventListener("error", () => { brokenImages.push(f.file); showBroken(); });
      g.appendChild(el("figure", {}, [img, el("figcaption", {}, [el("b", { text: f.title + ". " }), f.caption])]));
    }
    ps.appendChild(g);
  } else {
    ps.appendChild(el("p", { class: "warn", text: "Plots are unavailable" + (M.plots_unavailable ? ": " + M.plots_unavailable : "") + "." }));
  }
  root.appendChild(ps);

  if (M.regions && M.regions.length) {
    const sec = el("section", {}, [el("h2", { text: M.scene === "fig1" ? "Per object (fig1: one sphere per roughness)" : "Per object" })]);
    if (K > 1) sec.appendChild(el("p", { class: "note", text: `Medians over ${K} seeds, [min, max] their spread.` }));
    sec.appendChild(regionTable(M.equal_spp, "relMSE per object at equal spp"));
    if (M.equal_time) sec.appendChild(regionTable(M.equal_time, "relMSE per object at equal time"));
    sec.appendChild(tailTable(M.equal_spp, "The tail per object at equal spp: the worst pixel and the pixels more than 10\u00d7 off"));
    if (M.equal_time) sec.appendChild(tailTable(M.equal_time, "The tail per object at equal time"));
    root.appendChild(sec);
  }
  // ------------------------------------------------------------------ exact variance analysis
  function analysisSection(A) {
    const sec = el("section", {}, [el("h2", { text: "Exact variance analysis: V of one sample per object (no rendering)" })]);
    const compared = new Set(M.equal_spp.strategies.map((s) => s.strategy));
    const extra = A.strategies.filter((s) => !compared.has(s));
    sec.appendChild(el("p", { class: "note", text:
      `V = Var / I² of the ${A.heuristic}-heuristic direct estimator's one sample (one light sample plus one BSDF ` +
      `sample) at a shading point, computed by quadrature over the ${A.grid_resolution}² fine texels of the light ` +
      `table (envpis analyze, docs/analyzer.md): exact, no Monte Carlo noise, visibility ${A.visibility ? "traced" : "off"}. ` +
      `Per object: the geometric mean over up to ${A.points_per_object} first hits of camera rays ` +
      `(${A.points_analyzed} points, ${fmt(A.seconds, 3)} s). relMSE ≈ V / spp up to the pixel footprint and the ` +
      `sampler's stratification. product*: sampling exactly proportional to BSDF × cos × environment. The ` +
      `decomposition compares light samples alone (no BSDF sample, no MIS): env / product is what the BSDF proxy gains, ` +
      `product / exact-12 what its per-cell estimates cost against a perfect 12×12 top level, exact-12 / exact-48 ` +
      `what the 12×12 resolution costs; mis / product is the ratio of the estimators.` +
      (extra.length ? ` ${extra.join(" and ")}: analyzed for the decomposition, not compared.` : "") +
      (M.integrator !== "direct" ? " The analysis models direct lighting at the first hit, not the path integrator." : "") }));
    if (!A.objects.length) {
      sec.appendChild(el("p", { class: "warn", text: "No shading point with light to analyze." }));
      return sec;
    }
    const ratios = [["env_light/product_light", "env / product"], ["product_light/exact-12", "product / exact-12"],
      ["exact-12/exact-48", "exact-12 / exact-48"], ["mis/product", "mis / product"]];
    const th = (text, attrs) => el("th", Object.assign({ text: text }, attrs || {}));
    const group = { style: "text-align:center" };
    const t = el("table", { class: "analysis" }, [
      el("tr", {}, [th("object", { rowspan: "2" }), th("points", { rowspan: "2" }),
        th("V of the estimator", Object.assign({ colspan: String(A.strategies.length) }, group)), th("limit", group),
        th("light samples alone: V ratio", Object.assign({ colspan: "3" }, group)), th("estimator", group)]),
      el("tr", {}, A.strategies.map((s) => th(s)).concat([th("product*")], ratios.map((r) => th(r[1]))))]);
    for (const o of A.objects) {
      const vals = A.strategies.map((s) => o.v[s]);
      const best = Math.min(...vals.filter((v) => v !== null && v !== undefined));
      t.appendChild(el("tr", {}, [el("td", { text: regionLabel(o.name) }), el("td", { text: String(o.points) })]
        .concat(vals.map((v) => el("td", { class: v === best ? "best" : "", text: fmt(v, 3) })),
          [el("td", { text: fmt(o.v_product_limit, 3) })],
          ratios.map((r) => el("td", { text: fmt(o.ratios[r[0]], 3) })))));
    }
    sec.appendChild(t);
    return sec;
  }
  if (M.analysis) root.appendChild(analysisSection(M.analysis));
  else if (M.analysis_unavailable) root.appendChild(el("p", { class: "warn", text: "Analysis unavailable: " + M.analysis_unavailable + "." }));
  // ------------------------------------------------------------------ images with linked zoom
  const zoom = { x: W / 2, y: H / 2, side: Math.max(8, Math.round(Math.min(W, H) / 4)), pinned: false };
  // Start on the object where mis has the most error (fig1: usually a mid-roughness sphere).
  (function () {
    const mis = M.equal_spp.strategies.find((s) => s.strategy === "mis") || M.equal_spp.strategies[0];
    let best = null;
    for (const r of M.regions || []) {
      const e = (mis.regions.find((x) => x.id === r.id) || {}).relmse;
      if (r.centroid && e !== null && e !== undefined && (!best || e > best.e)) best = { r: r, e: e };
    }
    if (best) { zoom.x = best.r.centroid[0]; zoom.y = best.r.centroid[1]; }
  })();
  const markers = [], insets = [];
  function update() {
    const s = zoom.side;
    const x0 = Math.min(Math.max(zoom.x - s / 2, 0), Math.max(0, W - s));
    const y0 = Math.min(Math.max(zoom.y - s / 2, 0), Math.max(0, H - s));
    for (const m of markers) {
      m.style.display = "block";
      m.style.left = (100 * x0 / W) + "%";
      m.style.top = (100 * y0 / H) + "%";
      m.style.width = (100 * s / W) + "%";
      m.style.height = (100 * s / H) + "%";
    }
    for (const d of insets) {
      const px = d.clientWidth || 160;
      const k = px / s;
      d.style.backgroundSize = `${W * k}px ${H * k}px`;
      d.style.backgroundPosition = `${-x0 * k}px ${-y0 * k}px`;
    }
  }
  function track(wrap) {
    const at = (ev) => {
      const r = wrap.getBoundingClientRect();
      zoom.x = (ev.clientX - r.left) / r.width * W;
      zoom.y = (ev.clientY - r.top) / r.height * H;
      update();
    };
    wrap.addEventListener("mousemove", (ev) => { if (!zoom.pinned) at(ev); });
    wrap.addEventListener("click", (ev) => { zoom.pinned = !zoom.pinned; at(ev); });
  }
  function imageWithMarker(src, alt) {
    const marker = el("div", { class: "marker" });
    markers.push(marker);
    const wrap = el("div", { class: "imgwrap" }, [image(src, alt), marker]);
    track(wrap);
    return wrap;
  }
  function inset(src, label) {
    const d = el("div", { class: "inset", title: label });
    d.style.backgroundImage = `url("${src}")`;
    insets.push(d);
    return el("div", { style: "flex:1;min-width:0" }, [d, el("div", { class: "cap", style: "font-size:12px", text: label })]);
  }
  function legend() {
    const em = M.error_map;
    const stops = em.colormap.map((c, i) => `rgb(${c[0]},${c[1]},${c[2]}) ${(100 * i / (em.colormap.length - 1)).toFixed(1)}%`);
    const bar = el("div", { class: "bar" });
    bar.style.background = `linear-gradient(to right, ${stops.join(", ")})`;
    return el("div", { class: "legend" }, [
      el("span", { text: "error map: per-pixel relative squared error, 1e" + em.log10_min }), bar,
      el("span", { text: "1e" + em.log10_max + " (log scale)" })]);
  }
  function zoomControls() {
    const c = el("div", { class: "controls" }, [el("span", { text: "Zoom region: " })]);
    for (const f of [1 / 8, 1 / 4, 1 / 2]) {
      const side = Math.max(4, Math.round(Math.min(W, H) * f));
      const b = el("button", { type: "button", text: side + " px" });
      b.addEventListener("click", () => { zoom.side = side; update(); });
      c.appendChild(b);
    }
    if (M.regions && M.regions.length && M.regions[0].bbox) {
      c.appendChild(el("span", { text: "  Object: " }));
      for (const r of M.regions) {
        const b = el("button", { type: "button", text: regionLabel(r.name) });
        b.addEventListener("click", () => {
          zoom.x = r.centroid[0];
          zoom.y = r.centroid[1];
          zoom.side = Math.max(4, Math.min(Math.min(W, H), Math.max(r.bbox[2] - r.bbox[0], r.bbox[3] - r.bbox[1])));
          zoom.pinned = true;
          update();
        });
        c.appendChild(b);
      }
    }
    c.appendChild(el("div", { class: "note", text: "Hover over any image to move the zoomed region in all of them; " +
      "click to pin it (click again to follow the pointer)." }));
    return c;
  }
  function imageSection(block, title) {
    const sec = el("section", {}, [el("h2", { text: title }), zoomControls()]);
    const strip = el("div", { class: "insets" }, [inset(ref.png, "reference")]);
    for (const s of block.strategies) strip.appendChild(inset(s.images.png, `${s.strategy} (${s.spp} spp)`));
    const estrip = el("div", { class: "insets" }, [el("div", { style: "flex:1" })]);
    for (const s of block.strategies) estrip.appendChild(inset(s.images.error_png, `${s.strategy} error`));
    sec.appendChild(strip);
    sec.appendChild(estrip);
    sec.appendChild(legend());
    const grid = el("div", { class: "grid" });
    if (W / H > 2.2) grid.style.gridTemplateColumns = "1fr";
    const refPair = el("div", { class: "pair" }, [imageWithMarker(ref.png, "reference")]);
    if (W / H > 2.2) refPair.classList.add("side");
    grid.appendChild(el("div", { class: "card" }, [
      el("div", { class: "cap" }, [el("b", { text: "reference" }), el("span", { text: `${ref.strategy}, ${ref.spp} spp` })]),
      refPair]));
    for (const s of block.strategies) {
      const pair = el("div", { class: "pair" }, [imageWithMarker(s.images.png, s.strategy),
        imageWithMarker(s.images.error_png, s.strategy + " error map")]);
      if (W / H > 2.2) pair.classList.add("side");
      grid.appendChild(el("div", { class: "card" }, [
        el("div", { class: "cap" }, [el("b", { text: s.strategy }),
          el("span", { text: `${s.spp} spp, ${fmt(s.seconds, 3)} s, relMSE ` +
            (K > 1 ? `${fmt(s.relmse_seeds[0], 3)} (seed ${M.seed}; median over ${K} seeds ${fmt(s.relmse, 3)})` : fmt(s.relmse, 3)) +
            `; ${W / H > 2.2 ? "left" : "top"}: image, ${W / H > 2.2 ? "right" : "bottom"}: error map` })]),
        pair]));
    }
    sec.appendChild(grid);
    return sec;
  }
  root.appendChild(imageSection(M.equal_spp, `Images at equal spp (${M.equal_spp.spp} spp)`));
  if (M.equal_time) root.appendChild(imageSection(M.equal_time, `Images at equal time (${fmt(M.equal_time.budget_seconds, 3)} s)`));

  // ------------------------------------------------------------------ convergence numbers, bias, settings
  const conv = M.convergence || {};
  const names = M.equal_spp.strategies.map((s) => s.strategy).filter((n) => conv[n]);
  if (names.length) {
    const sec = el("section", {}, [el("h3", { text: "Convergence: relMSE at each spp" })]);
    const spps = conv[names[0]].map((p) => p.spp);
    const t = el("table", {}, [el("tr", {}, [el("th", { text: "spp" })].concat(names.map((n) => el("th", { text: n }))))]);
    spps.forEach((n, i) => t.appendChild(el("tr", {}, [el("td", { text: String(n) })].concat(
      names.map((s) => el("td", { text: fmt((conv[s][i] || {}).relmse, 3) }))))));
    sec.appendChild(t);
    root.appendChild(sec);
  }
  if (M.regions && M.regions.length) root.appendChild(biasTable(M.equal_spp));
  const st = el("section", {}, [el("h2", { text: "Settings" })]);
  st.appendChild(el("pre", { class: "cmd", text: M.command }));
  st.appendChild(el("p", { class: "note", text:
    `Reference: ${ref.strategy}, ${ref.spp} spp, seed ${ref.seed}, ${fmt(ref.seconds, 3)} s` +
    `${ref.cached ? " (from the cache " + ref.cache_dir + ")" : ""}; its own noise adds about ` +
    `${fmt(ref.relmse_floor, 2)} to every relMSE. Product options: ${JSON.stringify(M.product_options)}. ` +
    `Oracle: ${M.oracle_options.resolution}\u00b2 cells, ${M.oracle_options.directions} BSDF evaluations per cell. ` +
    `Table build seconds: ${JSON.stringify(M.table_seconds)}. envpis ${M.version}.` }));
  root.appendChild(st);

  window.addEventListener("resize", update);
  window.addEventListener("load", update);
  update();
})();
