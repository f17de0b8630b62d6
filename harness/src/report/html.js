// index.html's filters and self-check. No library, no network: the page works from file://.
(function () {
  "use strict";
  var errors = [];
  window.addEventListener("error", function (e) { errors.push(String(e.message)); });
  var VERDICTS = ["pass", "fail", "inconclusive", "error", "not_applicable"];
  var LISTED = ["fail", "inconclusive", "error"];
  function all(sel) { return Array.prototype.slice.call(document.querySelectorAll(sel)); }
  function num(el) { return el ? Number(el.textContent) : 0; }
  var verdictSel = document.getElementById("f-verdict");
  var manualSel = document.getElementById("f-manual");

  // `#verdict=fail&manual=BU%200620` (or the same as a query string).
  function fromUrl() {
    var want = {};
    (location.hash.slice(1) + "&" + location.search.slice(1)).split("&").forEach(function (kv) {
      var i = kv.indexOf("=");
      if (i > 0) { want[decodeURIComponent(kv.slice(0, i))] = decodeURIComponent(kv.slice(i + 1)); }
    });
    [[verdictSel, want.verdict], [manualSel, want.manual]].forEach(function (p) {
      if (p[1] !== undefined && all("#" + p[0].id + " option").some(function (o) { return o.value === p[1]; })) {
        p[0].value = p[1];
      }
    });
  }

  function verdictMatches(filter, counts) {
    if (filter === "") { return true; }
    var names = filter === "not_passed" ? LISTED : [filter];
    return names.some(function (v) { return counts(v) > 0; });
  }

  function apply() {
    var fv = verdictSel.value, fm = manualSel.value, shown = 0, cases = all("article.case");
    cases.forEach(function (el) {
      var ok = verdictMatches(fv, function (v) { return el.dataset.verdict === v ? 1 : 0; }) &&
        (fm === "" || el.dataset.doc === fm);
      el.hidden = !ok;
      if (ok) { shown += 1; }
    });
    all("#coverage tbody tr").forEach(function (tr) {
      tr.hidden = !(verdictMatches(fv, function (v) { return Number(tr.dataset[v]); }) &&
        (fm === "" || tr.dataset.doc === fm));
    });
    all("#errata tbody tr, #statements tbody tr, #coverage-map .map-row").forEach(function (el) {
      el.hidden = !(fm === "" || el.dataset.doc === fm);
    });
    var out = document.getElementById("shown");
    out.textContent = shown + " of " + cases.length + " listed cases shown";
    out.dataset.shown = String(shown);
  }

  function onChange() {
    var parts = [];
    if (verdictSel.value) { parts.push("verdict=" + encodeURIComponent(verdictSel.value)); }
    if (manualSel.value) { parts.push("manual=" + encodeURIComponent(manualSel.value)); }
    location.hash = parts.join("&");
    apply();
  }

  // The numbers the page shows must agree with each other.
  function selfCheck() {
    var problems = [], totals = {};
    VERDICTS.forEach(function (v) { totals[v] = 0; });
    ["device", "model"].forEach(function (kind) {
      if (!document.getElementById("totals-" + kind)) { return; }
      VERDICTS.forEach(function (v) {
        var sum = 0;
        all("#totals-" + kind + " tr.profile td[data-verdict='" + v + "']").forEach(function (td) { sum += num(td); });
        var total = num(document.getElementById("total-" + kind + "-" + v));
        if (sum !== total) { problems.push(kind + " " + v + ": profiles sum to " + sum + ", total says " + total); }
        totals[v] += total;
      });
    });
    LISTED.forEach(function (v) {
      var listed = all("article.case[data-verdict='" + v + "']").length;
      if (listed !== totals[v]) { problems.push(v + ": " + listed + " cases listed, " + totals[v] + " counted"); }
    });
    VERDICTS.forEach(function (v) {
      var sum = 0;
      all("#coverage tbody tr").forEach(function (tr) { sum += Number(tr.dataset[v]); });
      if (sum !== totals[v]) { problems.push("coverage " + v + ": " + sum + ", totals " + totals[v]); }
    });
    // The not-applicable reasons add up to the not-applicable cases.
    var reasons = all("#not-applicable tbody tr");
    if (reasons.length) {
      var na = 0;
      reasons.forEach(function (tr) { na += Number(tr.dataset.n); });
      if (na !== totals.not_applicable) { problems.push("not applicable by reason: " + na + ", totals " + totals.not_applicable); }
    }
    // Each manual's coverage map holds as many statements as its row of totals says.
    var mapped = all("#coverage-map .map-row").map(function (row) {
      var n = 0;
      Array.prototype.forEach.call(row.querySelectorAll("i[data-n]"), function (i) { n += Number(i.dataset.n); });
      return n;
    });
    var listed = all("#statements tr.total").map(function (tr) { return Number(tr.dataset.statements); });
    if (mapped.join(",") !== listed.join(",")) { problems.push("coverage map " + mapped.join(",") + ", statement totals " + listed.join(",")); }
    problems = problems.concat(errors);
    var out = document.getElementById("selfcheck");
    out.dataset.ok = problems.length ? "false" : "true";
    out.textContent = problems.length ? "self-check failed: " + problems.join("; ") : "self-check ok";
  }

  verdictSel.addEventListener("change", onChange);
  manualSel.addEventListener("change", onChange);
  window.addEventListener("hashchange", function () { fromUrl(); apply(); });
  fromUrl();
  apply();
  selfCheck();
}());
