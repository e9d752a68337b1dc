// The page's words: one catalogue per language (i18n/<lang>.json), chosen from the browser's
// languages or the visitor's switch (kept in this browser), applied to elements marked with
// data-i18n (text), data-i18n-aria-label, data-i18n-placeholder and data-i18n-alt; the
// arguments of a marked element are in data-i18n-args (JSON), so a switch rewords everything.
"use strict";

window.SkyquillI18n = (() => {
  const LANGS = ["en", "zh-Hans"];
  const KEPT = "skyquill-lang";
  const ATTRS = ["aria-label", "placeholder", "alt"];
  const catalogues = {};
  const listeners = [];
  let lang = "en";

  // The first of the browser's languages we speak: any Chinese -> simplified, any English -> en.
  function fromBrowser(tags) {
    for (const tag of tags || []) {
      const low = String(tag).toLowerCase();
      if (low.startsWith("zh")) return "zh-Hans";
      if (low.startsWith("en")) return "en";
    }
    return "en";
  }

  function chosen() {
    let kept = null;
    try { kept = localStorage.getItem(KEPT); } catch (err) { /* private mode */ }
    if (LANGS.includes(kept)) return kept;
    return fromBrowser(navigator.languages && navigator.languages.length
      ? navigator.languages : [navigator.language]);
  }

  // ``key`` in the current language with {name} replaced; a count ``n`` picks key_one/_other.
  function t(key, args = {}) {
    const words = catalogues[lang] || {};
    let text = words[key];
    if (text === undefined && "n" in args) text = words[`${key}_${args.n === 1 ? "one" : "other"}`];
    if (text === undefined) text = (catalogues.en || {})[key] || key;
    const parts = text.split(/\{(\w+)\}/);  // text, name, text, name, ..., text
    let out = parts[0];
    for (let i = 1; i < parts.length; i += 2) {
      const value = args[parts[i]];
      if (!(parts[i] in args)) out += `{${parts[i]}}${parts[i + 1]}`;
      else if (value && typeof value === "object") out = meet(meet(out, inner(value)), parts[i + 1]);
      else out += String(value) + parts[i + 1];  // data (a number, the operator's words) as is
    }
    return out;
  }

  // An argument that is itself words ({ key, args }) is said in the same language.
  function inner(value) {
    return t(value.key, value.args || {});
  }

  // Where worded pieces meet, a Han character and a Latin letter or digit are set apart by a
  // space (Chinese typography): "由 2 号无人机", not "由2 号无人机".
  const HAN = /\p{Script=Han}/u;
  const LATIN = /[A-Za-z0-9]/;
  function meet(left, right) {
    const a = left.slice(-1);
    const b = right.charAt(0);
    const apart = (HAN.test(a) && LATIN.test(b)) || (LATIN.test(a) && HAN.test(b));
    return apart ? `${left} ${right}` : left + right;
  }

  function argsOf(el) {
    try { return JSON.parse(el.dataset.i18nArgs || "{}"); } catch (err) { return {}; }
  }

  // Mark ``el`` to say ``key`` (attr: an attribute instead of its text) and say it now.
  function set(el, key, args, attr) {
    if (attr) el.setAttribute(`data-i18n-${attr}`, key); else el.dataset.i18n = key;
    if (args) el.dataset.i18nArgs = JSON.stringify(args); else delete el.dataset.i18nArgs;
    apply(el);
  }

  function applyOne(el) {
    if (el.dataset.i18n) el.textContent = t(el.dataset.i18n, argsOf(el));
    for (const attr of ATTRS) {
      const key = el.getAttribute(`data-i18n-${attr}`);
      if (key) el.setAttribute(attr, t(key, argsOf(el)));
    }
  }

  function apply(root = document) {
    if (root.nodeType === 1) applyOne(root);
    const selector = ["[data-i18n]", ...ATTRS.map((a) => `[data-i18n-${a}]`)].join(",");
    for (const el of root.querySelectorAll(selector)) applyOne(el);
  }

  function use(next, keep = false) {
    lang = LANGS.includes(next) ? next : "en";
    document.documentElement.lang = lang;
    if (keep) { try { localStorage.setItem(KEPT, lang); } catch (err) { /* private mode */ } }
    for (const button of document.querySelectorAll("button.lang")) {
      button.textContent = (catalogues[button.dataset.lang] || {}).lang_name || button.dataset.lang;
      button.setAttribute("aria-pressed", String(button.dataset.lang === lang));
    }
    apply();
    for (const fn of listeners) fn(lang);
  }

  // The catalogues under ``base`` (the crew page keeps its own words apart).
  async function load(base = "/static/i18n") {
    await Promise.all(LANGS.map(async (name) => {
      try {
        const reply = await fetch(`${base}/${name}.json`, { credentials: "same-origin" });
        catalogues[name] = await reply.json();
      } catch (err) { catalogues[name] = {}; }
    }));
    for (const button of document.querySelectorAll("button.lang")) {
      button.addEventListener("click", () => use(button.dataset.lang, true));
    }
    use(chosen());
  }

  return { load, t, set, apply, onChange: (fn) => listeners.push(fn), lang: () => lang, fromBrowser };
})();
