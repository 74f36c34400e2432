// strandgraph report: the viewer (a row's picture, its reference, its FLIP
// map) and the self-check that tests/report.rs reads from the DOM.
"use strict";

// Selects thumb `t` (a row or a reference) into its section's viewer.
function select(section, t) {
  const v = section.querySelector(".viewer");
  if (!v || !t) return;
  section.querySelectorAll(".sel").forEach((e) => e.classList.remove("sel"));
  const row = t.dataset.row;
  section.querySelectorAll('[data-row="' + row + '"]').forEach((e) => e.classList.add("sel"));
  v.current = t;
  show(v, "row");
  window.lastViewer = v;
}

// Shows `mode` (row, ref or map) of the viewer's current thumb.
function show(v, mode) {
  const t = v.current;
  const src = { row: t.dataset.pic, ref: t.dataset.ref, map: t.dataset.map }[mode];
  if (!src) return;
  v.mode = mode;
  const img = v.querySelector("img.big");
  img.src = src;
  const names = { row: "", ref: "reference of ", map: "FLIP error of " };
  v.querySelector(".what").innerHTML = "";
  const b = document.createElement("b");
  b.textContent = names[mode];
  v.querySelector(".what").append(b, t.dataset.label);
  v.querySelector("a.full").href = src;
  v.querySelectorAll("button").forEach((btn) => {
    btn.classList.toggle("on", btn.dataset.mode === mode);
    btn.disabled = !{ row: t.dataset.pic, ref: t.dataset.ref, map: t.dataset.map }[btn.dataset.mode];
  });
}

// Between the row and its reference (the A/B a reader wants most).
function flip(v) {
  if (!v || !v.current) return;
  show(v, v.mode === "row" && v.current.dataset.ref ? "ref" : "row");
}

function setUp() {
  document.querySelectorAll("section.view").forEach((section) => {
    const v = section.querySelector(".viewer");
    if (!v) return;
    section.querySelectorAll(".thumb, tr[data-row]").forEach((el) => {
      el.addEventListener("click", () => {
        select(section, section.querySelector('.thumb[data-row="' + el.dataset.row + '"]'));
      });
    });
    const big = v.querySelector("img.big");
    const scale = () => big.classList.toggle("up", big.naturalWidth < big.clientWidth);
    big.addEventListener("load", scale);
    window.addEventListener("resize", scale);
    if (big.complete) scale();
    v.querySelector(".frame").addEventListener("click", () => {
      window.lastViewer = v;
      flip(v);
    });
    v.querySelectorAll("button").forEach((btn) => {
      btn.addEventListener("click", () => show(v, btn.dataset.mode));
    });
    select(section, section.querySelector('.thumb[data-row="' + v.dataset.row + '"]'));
  });
  document.addEventListener("keydown", (e) => {
    if (e.key === " " && window.lastViewer) {
      e.preventDefault();
      flip(window.lastViewer);
    }
  });
}

// Every picture decoded, every chart present, no script error: written
// to the body's data-report-check attribute, for a headless browser's
// DOM dump (tests/report.rs).
function check() {
  const body = document.body;
  const imgs = Array.from(document.images);
  const broken = imgs.filter((i) => !(i.complete && i.naturalWidth > 0)).map((i) => i.getAttribute("src"));
  const charts = document.querySelectorAll("figure.chart[data-chart] svg").length;
  const want = { images: +body.dataset.expectImages, charts: +body.dataset.expectCharts };
  const problems = [];
  if (imgs.length !== want.images) problems.push("images " + imgs.length + " of " + want.images);
  if (broken.length) problems.push("broken images: " + broken.join(" "));
  if (charts !== want.charts) problems.push("charts " + charts + " of " + want.charts);
  if (window.reportErrors.length) problems.push("errors: " + window.reportErrors.join(" | "));
  body.dataset.reportCheck = problems.length ? "fail: " + problems.join("; ") : "ok";
  body.dataset.reportCounts = "images=" + imgs.length + " charts=" + charts;
}

setUp();
if (document.readyState === "complete") check();
else window.addEventListener("load", check);
