// The viewers and the graph layout as one script (window.GraphvisionViewers), for pages
// that inline it, such as report.html: no network, no module loader.
export { GraphView, STATE_COLOURS } from "./graphview.js";
export { layoutGraph, overlaps, downstream } from "./layout.js";
export { colourise, finiteRange, labelColour, ticks, viridis } from "./colormap.js";
export { docHtml } from "./tex.js";
export { drawColourBar, floatMapViewer, ImageViewer, pointCloudViewer, scalarViewer, tableViewer } from "./viewers.js";
export { readValue, widgetSpec } from "./widgets.js";
