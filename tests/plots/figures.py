"""What the figure tests share: the figures a plotting function would save, kept open for reading, and every
text a figure shows."""

from __future__ import annotations

from capmap.plots.common import plt


def keep_figures(monkeypatch, *modules):
    """Fixture body: each of ``modules``' ``save`` keeps the figure instead; yields the list, closes them after."""
    kept = []
    for module in modules:
        monkeypatch.setattr(module, "save", lambda fig, out_png, rect=None: kept.append(fig))
    yield kept
    for fig in kept:
        plt.close(fig)


def figure_texts(fig) -> str:
    """Every text of ``fig`` and its subfigures: titles, axis labels, texts, legends."""
    out = [fig._suptitle.get_text() if fig._suptitle else ""]
    for sub in getattr(fig, "subfigs", []):
        out.append(figure_texts(sub))
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()] + [t.get_text() for t in ax.texts]
        if ax.get_legend():
            out += [t.get_text() for t in ax.get_legend().get_texts()]
    out += [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    return "\n".join(out + [t.get_text() for t in fig.texts])
