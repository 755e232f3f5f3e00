"""Plot output shared by the examples: PNG files, no display needed."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402


def save_figure(figure, path):
    figure.tight_layout()
    figure.savefig(path, dpi=200, bbox_inches="tight")  # print quality; legends beside the axes kept
    plt.close(figure)
