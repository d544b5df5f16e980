// An op's docstring (reStructuredText) as HTML with its formulas typeset by KaTeX.
const escape = (s) => s.replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);

function math(tex, display) {
  const katex = globalThis.katex;
  if (!katex) return `<code>${escape(tex)}</code>`;
  try {
    return katex.renderToString(tex, { displayMode: display, throwOnError: false });
  } catch (e) {
    return `<code>${escape(tex)}</code>`;
  }
}

// Paragraphs; ``.. math::`` blocks in display mode; :math:`x` inline; section underlines dropped.
export function docHtml(doc) {
  const lines = doc.split("\n");
  const out = [];
  let para = [];
  const flush = () => {
    if (para.length) out.push(`<p>${inline(para.join(" "))}</p>`);
    para = [];
  };
  for (let i = 0; i < lines.length; i++) {
    const line = lines[i];
    if (/^\.\. math::/.test(line.trim())) {
      flush();
      const body = [];
      const rest = line.trim().slice(9).trim();
      if (rest) body.push(rest);
      while (i + 1 < lines.length && (lines[i + 1].trim() === "" || /^\s/.test(lines[i + 1]))) {
        i += 1;
        if (lines[i].trim()) body.push(lines[i].trim());
        else if (body.length && i + 1 < lines.length && !/^\s/.test(lines[i + 1])) break;
      }
      out.push(`<div class="gv-math">${math(body.join(" "), true)}</div>`);
    } else if (/^[-=~^]{3,}$/.test(line.trim())) {
      const head = para.pop();
      flush();
      if (head) out.push(`<h4>${escape(head)}</h4>`);
    } else if (!line.trim()) {
      flush();
    } else {
      para.push(line.trim());
    }
  }
  flush();
  return out.join("\n");
}

export function inline(text) {
  const parts = text.split(/(:math:`[^`]+`)/g);
  return parts.map((p) => {
    const m = p.match(/^:math:`([^`]+)`$/);
    if (m) return math(m[1], false);
    return escape(p).replace(/``([^`]+)``/g, "<code>$1</code>").replace(/`([^`]+)`_?/g, "<em>$1</em>");
  }).join("");
}
