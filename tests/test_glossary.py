"""Every abbreviation of a report spelled out at its first use, once, and never inside code or a tag."""

from __future__ import annotations

from housner.reports.glossary import GLOSSARY, glossary_html, spell_out


def test_first_use_is_spelled_out_once():
    page = "<header><p>Seed paper: 100 RDK motions</p></header><p>KS 0.09; KS again; the seed paper</p>"
    out = spell_out(page)
    assert "Seed paper (Bachmann et al., COMPDYN 2017):" in out
    assert "100 RDK (Rezaeian &amp; Der Kiureghian) motions" in out
    assert out.count("Kolmogorov") == 1 and "KS (Kolmogorov&ndash;Smirnov) 0.09; KS again" in out
    assert out.count("COMPDYN") == 1  # "seed paper" later on is the same term: not spelled out twice


def test_code_tags_and_words_that_contain_an_abbreviation_are_left_alone():
    page = '<p><code>KS</code> <img alt="KS" src="data:x"> MASKS KS-test CI</p><style>.KS{}</style>'
    out = spell_out(page)
    assert "<code>KS</code>" in out and 'alt="KS"' in out and "MASKS KS-test" in out and ".KS{}" in out
    assert "CI (confidence interval)" in out


def test_the_glossary_defines_every_term_with_an_anchor():
    html = glossary_html()
    for key, _, text in GLOSSARY:
        assert f'id="glossary-{key}"' in html and len(text) > 40
    assert 'id="glossary-chaos-floor"' in html
