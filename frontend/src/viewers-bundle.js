// The viewers and the graph layout as one script (window.GraphvisionViewers), for pages
// that inline it, such as report.html: no network, no module loader.
export { GraphView, STATE_COLOURS } from "./graphview.js";
export { layoutGraph, overlaps, downstream } from "./layout.js";
export { autoRange, colourise, finiteRange, labelColour, ticks, viridis } from "./colormap.js";
export { docHtml } from "./tex.js";
export { canvasOf, cloudColours, drawColourBar, floatMapViewer, ImageViewer, pointCloudViewer, scalarViewer,
  tableViewer, tint } from "./viewers.js";
export { clipLine, epipolarLine, epipolarSegments, matchSegments, pairViewer, PAIR_GAP, sideBySide, spread } from "./pairs.js";
export { confusionShares, confusionViewer, curvesViewer, niceTicks, samplesRow } from "./charts.js";
export { classifierPanel, cloudPanel, curvesPanel, epipolarPanel, maskLayer, matchesPanel } from "./panels.js";
export { changeText, readValue, widgetSpec } from "./widgets.js";
