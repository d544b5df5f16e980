// Build the studio's static files into graphvision/studio/static (run: npm ci && npm run build).
// studio.js: the page; viewers.js: the viewers and the layout as one script that
// report.html can inline (window.GraphvisionViewers); KaTeX and the licences beside them.
import { build } from "esbuild";
import { cpSync, mkdirSync, readdirSync, rmSync, writeFileSync, readFileSync } from "node:fs";

const out = "../graphvision/studio/static";
rmSync(out, { recursive: true, force: true });
mkdirSync(`${out}/katex/fonts`, { recursive: true });
mkdirSync(`${out}/licences`, { recursive: true });
const common = { bundle: true, minify: true, target: "es2020", legalComments: "none", logLevel: "warning" };
await build({ ...common, entryPoints: ["src/studio.js"], outfile: `${out}/studio.js`, format: "iife" });
await build({ ...common, entryPoints: ["src/viewers-bundle.js"], outfile: `${out}/viewers.js`,
  format: "iife", globalName: "GraphvisionViewers" });
// report.html's graph layout, owned by the views package (which may not import the studio's)
const views = "../graphvision/views/static";
rmSync(views, { recursive: true, force: true });
mkdirSync(`${views}/licences`, { recursive: true });
await build({ ...common, entryPoints: ["src/report-graph.js"], outfile: `${views}/graph.js`,
  format: "iife", globalName: "GraphvisionGraph" });
cpSync("node_modules/@dagrejs/dagre/LICENSE", `${views}/licences/dagre.LICENSE`);
cpSync("node_modules/@dagrejs/graphlib/LICENSE", `${views}/licences/graphlib.LICENSE`);
cpSync("src/studio.css", `${out}/studio.css`);
cpSync("index.html", `${out}/index.html`);
const katex = "node_modules/katex/dist";
cpSync(`${katex}/katex.min.js`, `${out}/katex/katex.min.js`);
cpSync(`${katex}/katex.min.css`, `${out}/katex/katex.min.css`);
for (const font of readdirSync(`${katex}/fonts`).filter((f) => f.endsWith(".woff2"))) {
  cpSync(`${katex}/fonts/${font}`, `${out}/katex/fonts/${font}`);
}
cpSync("node_modules/katex/LICENSE", `${out}/licences/katex.LICENSE`);
cpSync("node_modules/@dagrejs/dagre/LICENSE", `${out}/licences/dagre.LICENSE`);
cpSync("node_modules/@dagrejs/graphlib/LICENSE", `${out}/licences/graphlib.LICENSE`);
const lock = JSON.parse(readFileSync("package-lock.json", "utf8"));
const version = (name) => lock.packages[`node_modules/${name}`].version;
writeFileSync(`${out}/licences/README.txt`,
  `Built by frontend/build.mjs from the npm registry (package-lock.json pins every version):\n` +
  `  @dagrejs/dagre ${version("@dagrejs/dagre")} (MIT), @dagrejs/graphlib ${version("@dagrejs/graphlib")} (MIT): graph layout, bundled into studio.js and viewers.js\n` +
  `  katex ${version("katex")} (MIT): formulas, katex/\n` +
  `  esbuild ${version("esbuild")} (MIT): the bundler (build time only)\n`);
writeFileSync(`${views}/licences/README.txt`,
  `Built by frontend/build.mjs from the npm registry (package-lock.json pins every version):\n` +
  `  @dagrejs/dagre ${version("@dagrejs/dagre")} (MIT), @dagrejs/graphlib ${version("@dagrejs/graphlib")} (MIT): ` +
  `graph layout, bundled into graph.js, which report.html inlines\n`);
console.log(`built ${out} and ${views}`);
