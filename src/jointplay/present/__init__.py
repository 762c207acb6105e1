"""Presentation at the edge: text reports, the 3D scene, figures, the HTML
report and the files a study writes."""
