/* The viewer's constants, the run data read from the page, and small DOM and number helpers. */
const SVG = "http://www.w3.org/2000/svg";
const STATUS = { S: "SUCCESS", F: "FAILURE", R: "RUNNING", "-": "INVALID", I: "IDLE" };
const SPEEDS = [1, 5, 20];
const EPS = 1e-9;
const DATA = JSON.parse(document.getElementById("run-data").textContent);
const app = document.getElementById("app");

/* ------------------------------------------------------------------ small helpers */

function el(tag, attrs, text) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  return node;
}

function sv(tag, attrs, text) {
  const node = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  return node;
}

function titled(node, text) {
  node.appendChild(sv("title", {}, text));
  return node;
}

/** The last index i of the sorted array a with a[i] <= v, or -1. */
function lastAtOrBefore(a, v) {
  let lo = 0;
  let hi = a.length - 1;
  let found = -1;
  while (lo <= hi) {
    const mid = (lo + hi) >> 1;
    if (a[mid] <= v) {
      found = mid;
      lo = mid + 1;
    } else {
      hi = mid - 1;
    }
  }
  return found;
}

function fmt(v, digits) {
  return v === null || v === undefined ? "—" : Number(v).toFixed(digits);
}

function valueText(v) {
  return typeof v === "string" ? v : JSON.stringify(v);
}

function hue(text) {
  let h = 0;
  for (let i = 0; i < text.length; i++) h = (h * 31 + text.charCodeAt(i)) % 360;
  return "hsl(" + h + ", 55%, 62%)";
}
