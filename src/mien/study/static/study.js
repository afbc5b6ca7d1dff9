// The study page: consent -> instructions -> one stimulus at a time -> completion. Every answer is POSTed and
// committed before the next stimulus appears; reopening the same link resumes where the participant stopped.
"use strict";

const $ = (id) => document.getElementById(id);
let state = null;          // the /api/session answer
let position = 0;          // index into state.sequence
let shows = 0;             // plays of the current stimulus
let sending = false;

function showPage(id) {
  for (const page of document.querySelectorAll(".page")) page.hidden = page.id !== id;
}

function fail(message) {
  $("failure-text").textContent = message;
  showPage("failure");
}

async function post(path, body, attempts = 6) {
  // Retries on 503 (database busy) and network errors with a growing delay; other errors are final.
  let delay = 300;
  for (let attempt = 1; ; attempt++) {
    let response;
    try {
      response = await fetch(path, {method: "POST", headers: {"Content-Type": "application/json"},
                                    body: JSON.stringify(body)});
    } catch (error) {
      response = null;
    }
    if (response && response.ok) return response.json();
    if (response && response.status !== 503) {
      let detail = response.statusText;
      try { detail = (await response.json()).detail; } catch (error) { /* keep the status text */ }
      throw new Error(typeof detail === "string" ? detail : JSON.stringify(detail));
    }
    if (attempt >= attempts) throw new Error("the server cannot save answers right now; please try again in a moment");
    await new Promise((resolve) => setTimeout(resolve, delay));
    delay = Math.min(delay * 2, 4000);
  }
}

function finish(info) {
  showPage("done");
  if (info.completion_code) {
    $("code").textContent = info.completion_code;
    $("code-line").hidden = false;
  }
  if (info.redirect_url) {
    $("redirect-link").href = info.redirect_url;
    $("redirect-line").hidden = false;
    setTimeout(() => { window.location.href = info.redirect_url; }, 3000);
  }
}

function buildQuestions() {
  const form = $("questions");
  form.textContent = "";
  for (const q of state.questions) {
    const set = document.createElement("fieldset");
    set.dataset.key = q.key;
    const legend = document.createElement("legend");
    const text = document.createElement("span");
    text.className = "q-text";
    text.textContent = q.text;
    legend.appendChild(text);
    set.appendChild(legend);
    const scale = document.createElement("div");
    scale.className = "scale";
    scale.appendChild(Object.assign(document.createElement("span"), {textContent: q.low_text}));
    for (let value = q.low; value <= q.high; value++) {
      const label = document.createElement("label");
      const input = Object.assign(document.createElement("input"), {type: "radio", name: q.key, value: String(value)});
      input.addEventListener("change", updateNext);
      label.appendChild(input);
      label.appendChild(document.createTextNode(String(value)));
      scale.appendChild(label);
    }
    scale.appendChild(Object.assign(document.createElement("span"), {textContent: q.high_text}));
    set.appendChild(scale);
    form.appendChild(set);
  }
}

function ratings() {
  const out = {};
  for (const q of state.questions) {
    const checked = document.querySelector(`input[name="${CSS.escape(q.key)}"]:checked`);
    if (checked) out[q.key] = Number(checked.value);
  }
  return out;
}

function updateNext() {
  $("next-button").disabled = sending || Object.keys(ratings()).length !== state.questions.length || shows < 1;
}

async function play() {
  const item = state.sequence[position];
  shows += 1;
  $("shows").textContent = shows === 1 ? "" : `(played ${shows} times)`;
  const video = $("video");
  video.currentTime = 0;
  try { await video.play(); } catch (error) { /* autoplay refused: the participant presses Play again */ }
  updateNext();
  try {
    const stored = await post("/api/show", {participant: state.participant, stimulus: item.stimulus, nr_shows: shows});
    shows = Math.max(shows, stored.nr_shows);
  } catch (error) {
    $("trial-error").textContent = error.message;
    $("trial-error").hidden = false;
  }
}

function showTrial() {
  const item = state.sequence[position];
  showPage("trial");
  $("trial-error").hidden = true;
  $("counter").textContent = `Video ${position + 1} of ${state.sequence.length}`;
  $("description").hidden = !item.description;
  $("description").textContent = item.description ? `“${item.description}”` : "";
  $("questions").reset();
  shows = state.nr_shows[item.stimulus] || 0;
  const video = $("video");
  video.src = item.url;
  video.dataset.stimulus = item.stimulus;
  video.onloadeddata = () => { video.onloadeddata = null; play(); };
  video.onerror = () => {
    $("trial-error").textContent = "This video could not be loaded. Please reload the page; your answers so far are saved.";
    $("trial-error").hidden = false;
  };
  video.load();
  window.scrollTo(0, 0);
  updateNext();
}

async function next() {
  if (sending) return;
  const item = state.sequence[position];
  sending = true;
  updateNext();
  try {
    const result = await post("/api/answer", {participant: state.participant, stimulus: item.stimulus,
                                              position: item.position, ratings: ratings(), nr_shows: shows});
    state.nr_shows = result.nr_shows;
    if (result.done) { finish(result); return; }
    position = result.next_position;
    showTrial();
  } catch (error) {
    $("trial-error").textContent = `Not saved: ${error.message}`;
    $("trial-error").hidden = false;
  } finally {
    sending = false;
    updateNext();
  }
}

async function start() {
  const params = new URLSearchParams(window.location.search);
  try {
    state = await post("/api/session", {participant: params.get("participant")});
  } catch (error) {
    fail(error.message);
    return;
  }
  if (params.get("participant") !== state.participant) {
    params.set("participant", state.participant);
    history.replaceState(null, "", `${window.location.pathname}?${params}`);
  }
  document.title = state.study;
  buildQuestions();
  $("consent-text").textContent = state.consent_text;
  $("instructions-text").textContent = state.instructions_text;
  position = state.next_position;
  if (state.done) { finish(state); return; }
  if (!state.consent_given) { showPage("consent"); return; }
  if (state.answered > 0) {
    $("instructions-title").textContent = "Welcome back";
    $("start-button").textContent = `Continue with video ${position + 1} of ${state.sequence.length}`;
  }
  showPage("instructions");
}

$("consent-check").addEventListener("change", (event) => { $("consent-button").disabled = !event.target.checked; });
$("consent-button").addEventListener("click", async () => {
  $("consent-button").disabled = true;
  try {
    await post("/api/consent", {participant: state.participant});
    showPage("instructions");
  } catch (error) {
    fail(error.message);
  }
});
$("start-button").addEventListener("click", showTrial);
$("replay-button").addEventListener("click", play);
$("next-button").addEventListener("click", next);
$("questions").addEventListener("submit", (event) => event.preventDefault());
start();
