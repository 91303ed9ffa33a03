// rvmsim console: the page's logic (hand-written, no libraries).
// Every string from the server is set with textContent, never as HTML.
// Latest value wins: at most one evaluation is in flight; a newer value replaces the pending
// one, so a dragged slider never queues stale frames, and an answer is shown only once it
// and its picture are complete (nothing older than the newest request is ever shown).
// While a slider is dragged the page asks for a draft picture (the EC image, made with the
// ECs); on release, and for typed values, keys and loaded candidates, the full picture,
// fetched in parallel with the ECs.
// The setting lives in the URL's fragment (#zoom=0.9&annotate=1&b=…), so a reload or a
// shared link restores it; every value is checked against its parameter's range before it
// enters the setting.
"use strict";
(() => {
  const token = new URLSearchParams(location.search).get("token") || "";
  const $ = (id) => document.getElementById(id);
  const state = {
    session: null, current: {}, history: [], inflight: false, pending: null,
    annotate: false, b: null, bCaption: "", bResult: null, last: null, shown: null,
    timings: [], samples: [], server: [], frames: 0, inputs: 0, controls: {},
    dragging: false, lastDraft: false, lastWrite: undefined,
    // the parking guidelines: on/off, steering (% of the range), the last answer shown
    guides: {on: false, pct: 0, inflight: false, again: false, timer: null, last: null,
             lines: null, fetches: 0},
  };
  window.rvmConsole = state;  // for the tests and tools/bench_console.py

  class ApiError extends Error {
    constructor(message, key) { super(message); this.key = key || ""; }
  }

  // api(path): GET; api(path, body): POST of a JSON body (saves); api(path, null, query):
  // GET with ?q=JSON (evaluations, which change nothing).
  async function api(path, body, query) {
    const headers = {};
    if (body) headers["Content-Type"] = "application/json";
    if (token) headers["X-Rvm-Token"] = token;
    const url = query ? `${path}?q=${encodeURIComponent(JSON.stringify(query))}` : path;
    const r = await fetch(url, {method: body ? "POST" : "GET", headers,
                                body: body ? JSON.stringify(body) : undefined});
    let doc;
    try { doc = await r.json(); } catch (e) { doc = {error: `HTTP ${r.status}`}; }
    if (!r.ok) throw new ApiError(doc.error || `HTTP ${r.status}`, doc.key);
    return doc;
  }

  function say(text, kind) {
    const m = $("message");
    m.textContent = text;
    m.className = text ? kind : "";
  }

  function cell(row, text, cls) {
    const td = document.createElement("td");
    td.textContent = text;
    if (cls) td.className = cls;
    row.appendChild(td);
    return td;
  }

  const fmt = (x) => (x === null || x === undefined) ? "—" : String(Number(Number(x).toPrecision(4)));
  const num = (x) => (x === null || x === undefined) ? "—" : (Math.abs(x) >= 1e4 ? x.toExponential(3) : x.toFixed(3));
  const status = (i) => !i.enabled ? "off" : (i.passed ? "pass" : "fail");
  const names = () => state.session.order;
  const same = (a, b) => names().every((n) => a[n] === b[n]);

  // A picture's URL names its parameters (the server renders or reuses it on any request).
  function pictureUrl(kind, params) {
    return `/api/picture/${kind}.jpg?v=${state.session.server}&p=${names().map((n) => String(params[n])).join(",")}`;
  }

  // ------------------------------------------------------------------ values
  // Why `value` cannot be parameter `spec`'s value (the server's wording), or null.
  function problem(spec, value) {
    if (typeof value !== "number" || !Number.isFinite(value)) return `${spec.name}: must be a number`;
    if (value < spec.spec_low || value > spec.spec_high) {
      return `${spec.name}: ${value} is outside [${spec.spec_low}, ${spec.spec_high}]${spec.unit ? " " + spec.unit : ""}`;
    }
    return null;
  }

  function fieldError(name, text) {
    const c = state.controls[name];
    if (!c) return;
    c.error.textContent = text || "";
    c.error.hidden = !text;
    c.errorAt = text ? performance.now() : 0;
    c.box.setAttribute("aria-invalid", text ? "true" : "false");
  }

  // A value accepted beyond its search range (a candidate, the URL, a typed value) pins the
  // slider at an end: say so beside it rather than show a slider that does not move.
  function beyond(name) {
    const c = state.controls[name];
    const v = state.current[name];
    const s = c.spec;
    const out = v < s.low || v > s.high;
    c.beyond.textContent = out ? `${Number(v.toPrecision(7))} is outside the search range `
      + `[${fmt(s.low)}, ${fmt(s.high)}]${s.unit ? " " + s.unit : ""}: the slider stays at its `
      + `${v > s.high ? "right" : "left"} end` : "";
    c.beyond.hidden = !out;
    c.slider.classList.toggle("pinned", out);
  }

  // The candidates shown as A (the current setting) and B (the pinned one) are marked.
  function markCandidates() {
    for (const row of state.candidateRows || []) {
      const marks = [];
      if (same(row.params, state.current)) marks.push("A");
      if (state.b && same(row.params, state.b)) marks.push("B");
      row.mark.textContent = marks.join(" ");
      row.tr.dataset.mark = marks.join("");
    }
  }

  // ------------------------------------------------------------------ stale marking
  function markStale() {
    const s = state.shown;
    const stale = !s || s.annotate !== state.annotate || !same(s.params, state.current);
    document.body.dataset.stale = stale ? "1" : "0";
    for (const id of ["rvm-view", "score", "ec-view"]) $(id).classList.toggle("stale", stale);
    $("stale-note").hidden = !stale;
    $("rvm-view").setAttribute("aria-busy", stale ? "true" : "false");
    markCandidates();
  }

  // ------------------------------------------------------------------ evaluation
  function request(opts) {
    const o = opts || {};
    state.inputs += 1;
    const draft = !!o.draft && !state.annotate;
    state.lastDraft = draft;
    state.pending = {params: {...state.current}, annotate: state.annotate, draft,
                     guides: guidesWanted() ? state.guides.pct : null,
                     t0: o.t0 === undefined ? performance.now() : o.t0, initial: !!o.initial};
    markStale();
    writeUrl();
    if (!state.inflight) pump();
  }
  state.request = request;

  // The end of a drag: the draft shown (or pending) becomes the full picture.
  function release(t0) {
    state.dragging = false;
    if (state.lastDraft) request({t0});
  }

  // The picture's server time (its Server-Timing), once it has loaded; 0 if unknown.
  function renderMs(url) {
    const e = performance.getEntriesByName(new URL(url, location.href).href).pop();
    performance.clearResourceTimings();  // its buffer holds 250 entries
    return e && e.serverTiming && e.serverTiming.length ? e.serverTiming[0].duration : 0;
  }

  async function pump() {
    const job = state.pending;
    state.pending = null;
    if (!job) return;
    state.inflight = true;
    try {
      // A full job asks for the full picture at once, in parallel with the ECs, and for
      // the draft with them: whichever picture is ready first is shown with the ECs; the
      // full one replaces a draft as soon as it is decoded (before any newer value).
      const full = !job.draft && !job.annotate;
      let fullImg = null, fullReady = null, fullDone = false;
      if (full) {
        fullImg = new Image();
        fullImg.src = pictureUrl("display", job.params);
        fullReady = fullImg.decode().then(() => { fullDone = true; });
        fullReady.catch(() => {});  // awaited below
      }
      const query = {params: job.params, annotate: job.annotate, draft: job.draft || full,
                     inline: job.draft || full};
      if (job.guides !== null) query.guidelines = job.guides;
      const doc = await api("/api/evaluate", null, query);
      const tJson = performance.now();
      let img = fullImg;
      let quick = false;
      if (!full || !fullDone) {
        img = new Image();
        img.src = job.annotate ? doc.annotated : `data:image/jpeg;base64,${doc.draft_jpeg}`;
        quick = full;
      }
      await img.decode();
      const tImage = performance.now();
      show(doc, img, {...job, draft: job.draft || quick});
      const first = performance.now() - job.t0;
      const sample = {ms: first, draft: job.draft, full_ms: first, first: quick ? "draft" : "full"};
      const times = {...doc.timings_ms, page_json: tJson - job.t0, page_image: tImage - tJson,
                     page_table: performance.now() - tImage};
      if (quick) {
        await fullReady;
        showPicture(fullImg, job);
        sample.full_ms = performance.now() - job.t0;
      }
      if (full) times.render = renderMs(fullImg.src);
      state.timings.push(first);
      state.samples.push(sample);
      state.server.push(times);
      if (state.evalError) { say("", ""); state.evalError = false; }
    } catch (e) {
      rejected(e, job);
    } finally {
      state.inflight = false;
      if (state.pending) pump();
      else window.dispatchEvent(new Event("rvm-idle"));  // for tools that wait for frames
    }
  }

  // A value the server refused never stays in the setting: it goes back to the last value
  // shown, the message goes beside its field (and above the picture).
  function rejected(e, job) {
    say(e.message || String(e), "error");
    state.evalError = true;
    const key = e.key;
    if (key && key in state.controls) {
      fieldError(key, e.message);
      const good = state.shown ? state.shown.params[key] : state.session.start[key];
      state.current[key] = good;
      if (state.pending) state.pending.params[key] = good;
      syncControls();
      writeUrl();
    }
    markStale();
  }

  // The picture of `job` in place (its ECs are shown already).
  function showPicture(img, job) {
    const old = $("rvm");
    img.id = "rvm";
    img.alt = old.alt;
    img.dataset.quality = job.draft ? "draft" : "full";
    old.replaceWith(img);
    $("rvm-view").classList.toggle("annotated", !!job.annotate);
    showSize();
    const a = $("ab-a");
    a.src = img.src;
    a.hidden = false;
    $("ab-a-empty").hidden = true;
    if (state.shown) state.shown.draft = job.draft;
  }

  // The heading names the picture shown: the display of record, or the annotated image
  // (its own size), and the scale it is shown at when that is not 1:1.
  function showSize() {
    const img = $("rvm"), d = state.session.display;
    const annotated = $("rvm-view").classList.contains("annotated");
    const k = img.naturalWidth ? img.clientWidth / img.naturalWidth : 1;
    const at = Math.abs(k - 1) > 0.005 ? `, shown at ${Math.round(k * 100)} %` : "";
    $("rvm-size").textContent = annotated && img.naturalWidth
      ? `(annotated: ${img.naturalWidth}×${img.naturalHeight} px${at})`
      : `(${d.width}×${d.height} px${img.naturalWidth && !annotated ? at : ""})`;
  }

  function show(doc, img, job) {
    // an error beside a field is cleared by the first frame the user asked for after it
    // (not by the page's first frame: a link's refused value stays named until then)
    for (const [name, c] of Object.entries(state.controls)) {
      if (!job.initial && c.errorAt && c.errorAt < job.t0) fieldError(name, "");
    }
    showPicture(img, job);
    showEcs(doc);
    showRoi(doc.roi);
    $("ab-a-cap").textContent = `A: current — EC score ${fmt(doc.ec_score)}, ${doc.passed ? "all pass" : "not all pass"}`;
    state.last = doc;
    state.shown = {params: {...job.params}, annotate: job.annotate, draft: job.draft};
    state.frames += 1;
    document.body.dataset.frame = String(doc.frame);
    markStale();
    // the guidelines of this very setting, drawn with its picture; their ground error is
    // asked for once the setting is settled (not for every frame of a drag)
    if (doc.guidelines && doc.guidelines.steering_pct === state.guides.pct) drawGuides(doc.guidelines);
    else if (!guidesWanted()) drawGuides(null);
    if (guidesWanted() && !job.draft) fetchGuides();
    else markGuidesStale();
  }

  // ------------------------------------------------------------------ guidelines
  const guidesInfo = () => (state.session && state.session.guidelines) || {available: false};
  const guidesWanted = () => state.guides.on && guidesInfo().available;

  // The lines over the display picture (null: none), in its pixels (the SVG's viewBox).
  function drawGuides(g) {
    const svg = $("guides-svg");
    svg.replaceChildren();
    state.guides.lines = g;
    svg.toggleAttribute("hidden", !g);  // an SVG element has no .hidden property
    if (!g) return;
    svg.setAttribute("viewBox", `-0.5 -0.5 ${g.output.width} ${g.output.height}`);
    for (const line of g.lines) {
      for (const piece of line.pieces) {
        const pl = document.createElementNS(svg.namespaceURI, "polyline");  // the SVG's
        pl.setAttribute("points", piece.map((p) => `${p[0]},${p[1]}`).join(" "));
        pl.setAttribute("stroke", line.color);
        pl.setAttribute("stroke-width", String(g.line_width_px));
        pl.dataset.line = line.name;
        svg.appendChild(pl);
      }
    }
    document.body.dataset.guides = `${g.steering_pct}:${g.lines.length}`;
  }

  function steerText() {
    const r = guidesInfo().steering_range_deg || 0;
    const pct = state.guides.pct;
    return `${pct > 0 ? "+" : ""}${pct} % (${fmt(pct / 100 * r)}°)`;
  }

  // The answer of /api/guidelines is for the setting shown and this steering?
  const guidesCurrent = (doc) => !!state.shown && same(doc.params, state.shown.params)
    && doc.steering_pct === state.guides.pct;

  function markGuidesStale() {
    const last = state.guides.last;
    $("guides-view").classList.toggle("stale", !last || !guidesCurrent(last));
  }

  // The lines and the ground error of the setting shown (latest wins: one request in
  // flight; while a painted render is under way the server says "measuring" and the page
  // asks again).
  async function fetchGuides() {
    clearTimeout(state.guides.timer);
    state.guides.timer = null;
    if (!guidesWanted() || !state.shown) return;
    if (state.guides.inflight) { state.guides.again = true; return; }
    state.guides.inflight = true;
    state.guides.again = false;
    let measuring = false;
    try {
      const doc = await api("/api/guidelines", null,
                            {params: state.shown.params, steering_pct: state.guides.pct});
      state.guides.fetches += 1;
      if (guidesWanted() && guidesCurrent(doc)) {
        drawGuides(doc);
        showGuideError(doc);
        measuring = doc.error.static.status === "measuring"
          || doc.error.trajectory.status === "measuring";
      } else {
        state.guides.again = guidesWanted();
      }
    } catch (e) {
      say(`guidelines: ${e.message || e}`, "error");
    } finally {
      state.guides.inflight = false;
      markGuidesStale();
      if (state.guides.again) fetchGuides();
      else if (measuring) state.guides.timer = setTimeout(fetchGuides, 400);
    }
  }

  function groupSummary(name, g) {
    if (g.status === "measuring") return `${name}: measuring…`;
    if (g.status === "failed") return `${name}: not measured (${g.why})`;
    const w = g.worst;
    return w ? `${name}: worst ${fmt(w.offset_px)} px, ${fmt(w.offset_cm)} cm (${w.name})`
             : `${name}: not in the picture`;
  }

  function showGuideError(doc) {
    state.guides.last = doc;
    const e = doc.error;
    const measuring = e.static.status === "measuring" || e.trajectory.status === "measuring";
    const sum = $("guides-summary");
    sum.textContent = `Ground error — ${groupSummary("static", e.static)}; `
      + `${groupSummary(`trajectory at ${steerText()}`, e.trajectory)}`;
    sum.classList.toggle("measuring", measuring);
    $("guides-for").textContent = `(steering ${steerText()})`;
    const body = $("guides-table").tBodies[0];
    body.replaceChildren();
    for (const [what, g] of [["static", e.static], ["trajectory", e.trajectory]]) {
      if (g.status !== "ready") {
        const tr = document.createElement("tr");
        tr.className = g.status;
        cell(tr, g.status === "measuring" ? `${what}: measuring…` : `${what}: ${g.why}`).colSpan = 5;
        body.appendChild(tr);
        continue;
      }
      for (const l of g.lines) {
        const tr = document.createElement("tr");
        tr.dataset.line = l.name;
        if (g.worst && g.worst.name === l.name) tr.className = "worst";
        cell(tr, l.name);
        cell(tr, l.kind);
        cell(tr, l.steering_deg === null ? "—" : `${fmt(l.steering_deg)}°`, "num");
        cell(tr, l.offset_px === null ? "not in the picture" : fmt(l.offset_px), "num px");
        cell(tr, l.offset_cm === null ? "—" : fmt(l.offset_cm), "num cm");
        body.appendChild(tr);
      }
    }
    document.body.dataset.guidesError = measuring ? "measuring" : "ready";
  }

  // The toggle, the steering slider: new lines for the setting shown (its picture stays).
  function guidesChanged() {
    const on = guidesWanted();
    $("guides").checked = state.guides.on;
    $("steer").value = String(state.guides.pct);
    $("steer-out").textContent = steerText();
    $("guides-bar").hidden = !on;
    $("guides-view").hidden = !on;
    if (!on) {
      drawGuides(null);
      clearTimeout(state.guides.timer);
      document.body.dataset.guidesError = "";
    } else {
      $("guides-summary").textContent = "Ground error — measuring…";
      $("guides-summary").classList.add("measuring");
      fetchGuides();
    }
    markGuidesStale();
    writeUrl();
  }

  function buildGuides() {
    const g = guidesInfo();
    const box = $("guides");
    box.disabled = !g.available;
    if (!g.available) {
      state.guides.on = false;
      $("guides-label").title = g.why || "no guidelines for this scene";
      $("guides-why").textContent = `Guidelines not offered: ${g.why || "the scene has no running gear"}`;
      $("guides-why").hidden = false;
    }
    box.addEventListener("change", () => { state.guides.on = box.checked; guidesChanged(); });
    $("steer").addEventListener("input", () => {
      state.guides.pct = Number($("steer").value);
      guidesChanged();
    });
    guidesChanged();
  }

  function marginCell(tr, i) {
    const td = cell(tr, "", "margin");
    // a yes/no EC (1-1, 2-4) has no margin: ✓ or ✗, as in the report and the sign-off
    if (i.yes_no) { td.textContent = i.value === null ? "—" : (i.passed ? "✓" : "✗"); return; }
    const m = i.margin;
    if (m === null || m === undefined) { td.textContent = "—"; return; }
    td.dataset.margin = String(m);
    const bar = document.createElement("span");
    bar.className = "mbar";
    const fill = document.createElement("span");
    const c = Math.max(-1, Math.min(1, m));
    fill.className = "fill " + (m >= 0 ? "inside" : "outside");
    fill.style.width = `${Math.abs(c) * 50}%`;
    if (m >= 0) fill.style.left = "50%"; else fill.style.right = "50%";
    bar.appendChild(fill);
    const text = document.createElement("span");
    text.className = "mtext";
    text.textContent = `${m >= 0 ? "+" : "−"}${Math.abs(m * 100) >= 1000 ? ">999" : Math.round(Math.abs(m * 100))} %`;
    td.title = m >= 0 ? "inside its range (100 %: the middle, or a bound's size away)"
                      : "outside its range";
    td.append(bar, text);
  }

  function showEcs(doc) {
    const score = $("score");
    score.textContent = `EC score ${fmt(doc.ec_score)} · ${doc.passed ? "all pass" : "not all pass"}`;
    score.classList.remove("pass", "fail");
    score.classList.add(doc.passed ? "pass" : "fail");
    const failing = doc.ecs.filter((i) => i.enabled && !i.passed);
    $("failing").textContent = failing.length
      ? `fails: ${failing.map((i) => `${i.id} ${i.name}`).join(", ")}` : "";
    $("failing").hidden = !failing.length;
    const body = $("ec-table").tBodies[0];
    body.replaceChildren();
    const bItems = {};
    if (state.bResult) for (const i of state.bResult.ecs) bItems[i.id] = i;
    for (const i of doc.ecs) {
      const tr = document.createElement("tr");
      const st = status(i);
      tr.className = st;
      tr.dataset.ec = i.id;
      cell(tr, i.id);
      cell(tr, i.name);
      cell(tr, num(i.value), "num value");
      cell(tr, i.unit);
      cell(tr, `[${i.range[0] === null ? "–" : i.range[0]}, ${i.range[1] === null ? "–" : i.range[1]}]`, "num");
      marginCell(tr, i);
      cell(tr, i.score.toFixed(4), "num score");
      cell(tr, st, "res");
      const b = bItems[i.id];
      cell(tr, b ? num(b.value) : "", "num");
      cell(tr, b ? status(b) : "", b ? status(b) : "");
      body.appendChild(tr);
    }
  }

  function showRoi(points) {
    $("roi-line").setAttribute("points", points.map((p) => `${p[0]},${p[1]}`).join(" "));
  }

  // B: its ECs and its full picture; the placeholder stays until the picture is decoded.
  async function setB(params, caption) {
    try {
      const img = new Image();
      img.src = pictureUrl("display", params);
      const doc = await api("/api/evaluate", null, {params});
      await img.decode();
      state.b = {...params};
      state.bCaption = caption;
      state.bResult = doc;
      const b = $("ab-b");
      b.src = img.src;
      b.hidden = false;
      $("ab-b-empty").hidden = true;
      $("ab-b-cap").textContent = `B: ${caption} — EC score ${fmt(doc.ec_score)}, ${doc.passed ? "all pass" : "not all pass"}`;
      if (state.last) showEcs(state.last);
      markCandidates();
      writeUrl();
    } catch (e) {
      say(`B: ${e.message || e}`, "error");
    }
  }

  // ------------------------------------------------------------------ the URL
  function encodeParams(params) {
    return names().filter((n) => params[n] !== state.session.start[n])
      .map((n) => `${n}:${params[n]}`).join(",");
  }

  let urlTimer = null;
  function writeUrl() {  // at most every 200 ms (browsers throttle history updates)
    if (urlTimer !== null) return;
    urlTimer = setTimeout(() => {
      urlTimer = null;
      const h = new URLSearchParams();
      for (const n of names()) if (state.current[n] !== state.session.start[n]) h.set(n, String(state.current[n]));
      if (state.annotate) h.set("annotate", "1");
      if (state.guides.on) h.set("guides", "1");
      if (state.guides.on && state.guides.pct) h.set("steer", String(state.guides.pct));
      if (state.b) { h.set("b", encodeParams(state.b)); h.set("bname", state.bCaption); }
      const hash = h.toString();
      if (hash !== location.hash.slice(1)) {
        history.replaceState(null, "", location.pathname + location.search + (hash ? "#" + hash : ""));
      }
      document.body.dataset.url = location.hash;
    }, 200);
  }

  // The setting of the URL's fragment, each value checked; problems are listed, not used.
  function readUrl() {
    const h = new URLSearchParams(location.hash.slice(1));
    const current = {...state.session.start};
    const problems = [];
    const take = (target, name, text) => {
      const c = state.controls[name];
      if (!c) { problems.push(`${name}: unknown parameter`); return; }
      const v = text.trim() === "" ? NaN : Number(text);
      const p = problem(c.spec, v);
      if (p) { problems.push(p); fieldError(name, p); } else target[name] = v;
    };
    for (const [k, v] of h) {
      if (k === "annotate") state.annotate = v === "1";
      else if (k === "guides") state.guides.on = v === "1";
      else if (k === "steer") {
        const pct = Number(v);
        if (v.trim() !== "" && Number.isFinite(pct) && pct >= -100 && pct <= 100) state.guides.pct = Math.round(pct / 5) * 5;
        else problems.push(`steer: ${v} is not a steering angle in [-100, 100] %`);
      } else if (k !== "b" && k !== "bname") take(current, k, v);
    }
    let b = null;
    if (h.has("b")) {
      b = {...state.session.start};
      for (const part of h.get("b").split(",").filter((x) => x)) {
        const [n, v] = part.split(":");
        take(b, n, v === undefined ? "" : v);
      }
    }
    return {current, b, bname: h.get("bname") || "pinned setting", problems};
  }

  // ------------------------------------------------------------------ controls
  function syncControls() {
    for (const [name, c] of Object.entries(state.controls)) {
      c.slider.value = String(state.current[name]);
      c.box.value = String(Number(state.current[name].toPrecision(7)));
      beyond(name);
    }
    $("annotate").checked = state.annotate;
  }

  function commit(params, opts) {  // a new setting that undo can go back from
    state.history.push({...state.current});
    state.current = {...params};
    syncControls();
    request(opts);
  }

  function buildControl(spec) {
    const div = document.createElement("div");
    div.className = "control" + (spec.tuned ? " tuned" : "");
    div.dataset.param = spec.name;
    const human = `${spec.human} (${spec.name})`;
    const label = document.createElement("label");
    label.className = "name";
    label.textContent = `${spec.paper_name}${spec.unit ? " (" + spec.unit + ")" : ""}`;
    label.title = `${human}: ${spec.note}`;
    const slider = document.createElement("input");
    slider.type = "range";
    slider.min = String(spec.low);
    slider.max = String(spec.high);
    const span = spec.high - spec.low;
    slider.step = String(span / 1000);
    slider.name = spec.name;
    slider.setAttribute("aria-label", human);
    slider.title = human;
    const box = document.createElement("input");
    box.type = "number";
    box.step = "any";
    box.name = spec.name;
    box.setAttribute("aria-label", `${human} value`);
    const error = document.createElement("span");
    error.className = "field-error";
    error.id = `err-${spec.name}`;
    error.setAttribute("role", "alert");
    error.hidden = true;
    box.setAttribute("aria-describedby", error.id);
    const out = document.createElement("span");
    out.className = "beyond";
    out.hidden = true;
    const range = document.createElement("div");
    range.className = "range";
    const unit = spec.unit ? " " + spec.unit : "";
    range.textContent = (spec.tuned ? `tuned; search [${fmt(spec.low)}, ${fmt(spec.high)}]${unit}; ` : "not tuned; ")
      + `allowed [${spec.spec_low}, ${spec.spec_high}]${unit}; default ${spec.default}`;
    let before = null;
    slider.addEventListener("pointerdown", () => { before = {...state.current}; state.dragging = true; });
    slider.addEventListener("input", (ev) => {
      if (before === null) before = {...state.current};
      state.current[spec.name] = Number(slider.value);
      box.value = String(Number(Number(slider.value).toPrecision(7)));
      fieldError(spec.name, "");
      beyond(spec.name);
      request({draft: state.dragging, t0: ev.timeStamp || performance.now()});
    });
    slider.addEventListener("change", (ev) => {
      if (before !== null) state.history.push(before);
      before = null;
      release(ev.timeStamp || performance.now());
    });
    // PageUp/PageDown: 1 % of the slider's range (arrows: 0.1 %, its step)
    slider.addEventListener("keydown", (ev) => {
      if (ev.key !== "PageUp" && ev.key !== "PageDown") return;
      ev.preventDefault();
      const v = Math.min(spec.high, Math.max(spec.low,
        state.current[spec.name] + (ev.key === "PageUp" ? 1 : -1) * span / 100));
      commit({...state.current, [spec.name]: v}, {t0: ev.timeStamp});
    });
    box.addEventListener("change", () => {
      const v = box.value.trim() === "" ? NaN : Number(box.value);
      const p = problem(spec, v);
      if (p) {  // never enters the setting: the box goes back to the value in use
        const typed = box.value;
        fieldError(spec.name, `${p.replace(/^[^:]*: /, "")}${typed.trim() === "" || Number.isFinite(Number(typed)) ? "" : ` (${JSON.stringify(typed)})`}; kept ${Number(state.current[spec.name].toPrecision(7))}`);
        say(p, "error");
        state.evalError = true;  // cleared by the next frame shown
        box.value = String(Number(state.current[spec.name].toPrecision(7)));
        return;
      }
      fieldError(spec.name, "");
      commit({...state.current, [spec.name]: v});
    });
    label.htmlFor = `box-${spec.name}`;
    box.id = `box-${spec.name}`;
    slider.id = `slider-${spec.name}`;
    div.append(label, slider, box, error, out, range);
    state.controls[spec.name] = {slider, box, error, beyond: out, spec, errorAt: 0};
    return div;
  }

  function buildCandidates(cands) {
    const body = $("candidates").tBodies[0];
    state.candidateRows = [];
    if (!cands.length) {
      const tr = document.createElement("tr");
      cell(tr, "no run: the paper's defaults").colSpan = 5;
      body.appendChild(tr);
      return;
    }
    for (const c of cands) {
      const tr = document.createElement("tr");
      tr.dataset.rank = String(c.rank);
      const mark = document.createElement("span");
      mark.className = "mark";
      cell(tr, `#${c.rank}`).appendChild(mark);
      state.candidateRows.push({tr, params: c.params, mark});
      cell(tr, fmt(c.score), "num");
      cell(tr, c.passed ? "pass" : "fail", c.passed ? "pass" : "fail");
      cell(tr, c.differs || (c.rank === 1 ? "rank 1" : `trial ${c.trial}`));
      const td = cell(tr, "");
      const load = document.createElement("button");
      load.type = "button";
      load.textContent = "Load";
      load.className = "load";
      load.setAttribute("aria-label", `Load candidate ${c.rank}`);
      load.addEventListener("click", () => { commit(c.params); say(`loaded candidate #${c.rank}`, "ok"); });
      const asB = document.createElement("button");
      asB.type = "button";
      asB.textContent = "B";
      asB.className = "as-b";
      asB.setAttribute("aria-label", `Show candidate ${c.rank} as B`);
      asB.addEventListener("click", () => setB(c.params, `candidate #${c.rank}`));
      td.append(load, asB);
      body.appendChild(tr);
    }
  }

  async function write(path, what) {
    try {
      const doc = await api(path, {params: state.current, label: $("label").value});
      state.lastWrite = doc;
      say(`${what} ${doc.path}`, "ok");
      $("saved-path").textContent = doc.path;
      $("saved-command").textContent = doc.command || "";
      $("saved-command-row").hidden = !doc.command;
      $("saved").hidden = false;
    } catch (e) {
      say(e.message, "error");
    }
  }

  async function start() {
    let s;
    try {
      s = await api("/api/session");
    } catch (e) {
      say(e.message, "error");
      return;
    }
    state.session = s;
    document.title = `rvmsim console: ${s.vehicle}`;
    $("title").textContent = s.vehicle;
    const sub = `${s.description ? s.description + " — " : ""}${s.kind} ${s.source}; ${s.kind === "run" ? `scene ${s.scene_file}; ` : ""}criteria ${s.criteria}; ECs at ${s.ec_output.width}×${s.ec_output.height} px; saves into ${s.save_dir}`;
    $("subtitle").textContent = sub;
    $("subtitle").title = sub;
    $("rvm-size").textContent = `(${s.display.width}×${s.display.height} px)`;
    $("fisheye").src = s.fisheye.url;
    $("roi").setAttribute("viewBox", `0 0 ${s.fisheye.width} ${s.fisheye.height}`);
    const box = $("controls");
    for (const spec of s.controls) box.appendChild(buildControl(spec));
    const restored = readUrl();
    state.current = restored.current;
    syncControls();
    buildCandidates(s.candidates);
    buildGuides();
    $("annotate").addEventListener("change", (ev) => { state.annotate = ev.target.checked; request(); });
    $("undo").addEventListener("click", () => {
      if (!state.history.length) { say("nothing to undo", "ok"); return; }
      state.current = state.history.pop();
      syncControls();
      request();
    });
    $("reset").addEventListener("click", () => commit(s.start));
    $("pin").addEventListener("click", () => setB({...state.current}, "pinned setting"));
    $("save").addEventListener("click", () => write("/api/save", "saved"));
    $("report").addEventListener("click", () => write("/api/report", "wrote"));
    window.addEventListener("pointerup", (ev) => { if (state.dragging) release(ev.timeStamp); });
    window.addEventListener("resize", showSize);
    document.body.dataset.ready = "1";
    request({initial: true});
    if (restored.b) setB(restored.b, restored.bname);
    if (restored.problems.length) say(`not restored from the URL: ${restored.problems.join("; ")}`, "error");
  }

  start();
})();
