"""The derived report as a PDF, and its verification table: not part of the derivation
(derive/ writes generated/report.tex) nor of the installed package.

- ``report/identities.py``: the identities of the generated functions (pytest uses them too);
- ``python -m report.verify``: evaluates them and writes the LaTeX table;
- ``python -m report.pdf``: builds generated/report.tex into a PDF with pdflatex.
"""
