// MathJax 3 for pymdownx.arithmatex (generic mode), SVG output: no web fonts, works offline.
// The MathJax file itself is copied into the site by docs/gen_reference.py (on_files).
window.MathJax = {
  tex: {inlineMath: [["\\(", "\\)"]], displayMath: [["\\[", "\\]"]],
        processEscapes: true, processEnvironments: true},
  options: {ignoreHtmlClass: ".*|", processHtmlClass: "arithmatex"},
  svg: {fontCache: "global"}
};
