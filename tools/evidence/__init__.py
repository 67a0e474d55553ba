"""One command for the evidence: regenerates the figures the docs show and writes the results
page docs/results/index.html (run.py), and checks that page in a headless browser
(check_page.py)."""
