// The survey page: consent, one question per screen, answers stored as they are clicked.
// Everything it knows comes from /api/session: question numbers and anonymous animation names.
"use strict";

const TOKEN_KEY = "rmt-survey-token";
let session = null;      // the session view from the server
let current = 0;         // index into session.items of the question on screen
let shownAt = 0;         // performance.now() when the current question became visible
let busy = false;

function $(id) { return document.getElementById(id); }

function show(section) {
  for (const id of ["intro", "question", "done"]) { $(id).hidden = id !== section; }
}

function message(text) {
  const box = $("message");
  box.textContent = text || "";
  box.hidden = !text;
}

async function api(method, path, body) {
  const headers = { "Content-Type": "application/json" };
  const token = localStorage.getItem(TOKEN_KEY);
  if (token) { headers["Authorization"] = "Bearer " + token; }
  const response = await fetch(path, {
    method: method,
    headers: headers,
    body: body === undefined ? undefined : JSON.stringify(body),
    cache: "no-store",
  });
  let data = null;
  try { data = await response.json(); } catch (e) { data = null; }
  return { status: response.status, data: data };
}

function answeredItems() {
  return new Set(session.answers.map(function (a) { return a.item; }));
}

function gifUrl(name) { return "/gif/" + encodeURIComponent(name) + ".gif"; }

function preload(index) {
  const item = session.items[index];
  if (!item) { return; }
  for (const name of [item.left, item.right]) { new Image().src = gifUrl(name); }
}

// Upscale x2 with nearest-neighbour sampling (the CSS sets image-rendering: pixelated).
function scaleOnLoad(img) {
  img.onload = function () {
    img.style.width = (img.naturalWidth * 2) + "px";
    if ($("left").complete && $("right").complete) { shownAt = performance.now(); }
  };
}

function render() {
  const total = session.total;
  const done = answeredItems();
  if (session.finished) { show("done"); return; }
  while (current < total && done.has(session.items[current].item)) { current += 1; }
  if (current >= total) { finish(); return; }
  const item = session.items[current];
  $("progress-bar").style.width = (100 * done.size / total) + "%";
  $("progress-text").textContent = "Question " + (done.size + 1) + " of " + total;
  shownAt = performance.now();
  $("left").src = gifUrl(item.left);
  $("right").src = gifUrl(item.right);
  for (const b of document.querySelectorAll(".choice")) { b.disabled = false; }
  show("question");
  preload(current + 1);
}

async function answer(code) {
  if (busy || !session) { return; }
  busy = true;
  for (const b of document.querySelectorAll(".choice")) { b.disabled = true; }
  const item = session.items[current];
  const ms = Math.max(0, Math.round(performance.now() - shownAt));
  try {
    const r = await api("POST", "/api/answer", { item: item.item, answer: code, ms: ms });
    if (r.status === 201 || r.status === 409) {
      // 409: this question was answered before (e.g. a retried click); the first answer stands.
      if (r.status === 201) { session.answers.push({ item: item.item, answer: code }); }
      else { await reload(); busy = false; return; }
      message("");
      current += 1;
      render();
    } else if (r.status === 401) {
      localStorage.removeItem(TOKEN_KEY);
      message("Your session is not known to the server; please start again.");
      show("intro");
    } else {
      message("Your answer could not be stored (" + ((r.data && r.data.error) || r.status) + "). Please try again.");
      for (const b of document.querySelectorAll(".choice")) { b.disabled = false; }
    }
  } catch (e) {
    message("The server cannot be reached. Please check your connection and click again.");
    for (const b of document.querySelectorAll(".choice")) { b.disabled = false; }
  }
  busy = false;
}

async function finish() {
  const r = await api("POST", "/api/finish");
  if (r.status === 200) { session = r.data; show("done"); message(""); }
  else { message("Could not finish (" + ((r.data && r.data.error) || r.status) + "). Please reload the page."); }
}

async function reload() {
  const r = await api("GET", "/api/session");
  if (r.status === 200) { session = r.data; current = 0; render(); return true; }
  localStorage.removeItem(TOKEN_KEY);
  return false;
}

async function start() {
  $("start").disabled = true;
  const r = await api("POST", "/api/session", { consent: true });
  if (r.status === 201) {
    localStorage.setItem(TOKEN_KEY, r.data.token);
    session = r.data;
    current = 0;
    message("");
    render();
  } else {
    message("Could not start (" + ((r.data && r.data.error) || r.status) + ").");
    $("start").disabled = false;
  }
}

document.addEventListener("DOMContentLoaded", async function () {
  scaleOnLoad($("left"));
  scaleOnLoad($("right"));
  $("consent-check").addEventListener("change", function () { $("start").disabled = !this.checked; });
  $("start").addEventListener("click", start);
  for (const b of document.querySelectorAll(".choice")) {
    b.addEventListener("click", function () { answer(b.dataset.answer); });
  }
  if (localStorage.getItem(TOKEN_KEY)) {
    try { if (await reload()) { return; } } catch (e) { /* fall through to the intro */ }
  }
  show("intro");
});
