"""Two estimates of the room's category, one from the scan and one from photographs, as one.

The rule, and why:

- **Product, renormalised.** The scan's geometry and a photograph's texture are evidence
  about the room obtained independently of each other. With a uniform prior over the
  categories, Bayes' rule gives ``P(N | scan, image) ∝ P(N | scan) · P(N | image)``: the
  categories both sources find likely are reinforced, and a source that cannot tell two
  categories apart leaves the other to decide. (An average would instead let a confident
  wrong source drag the result halfway towards it.)
- **A floor.** Before multiplying, each distribution is mixed with the uniform one:
  ``(1 - ε) · P + ε / K`` over the K room categories. A classifier trained on three
  categories gives exactly 0 to the twenty-one others, and a calibrated probability can
  round to 0; without the floor one source's zero would veto a category the other is sure
  of, whatever the evidence. ε is the chance that a source is simply wrong; 0.05 keeps a
  confident source decisive (a 0.9 against 0.1 stays about 9 to 1) while no category
  becomes impossible.
"""

from __future__ import annotations

from collections.abc import Mapping

from .._rules import Interval, check_param
from ..ontology import room_categories, room_distribution

__all__ = ["ROOM_PRIOR_FLOOR", "combine_room_priors"]

#: Share ε of the uniform distribution mixed into each source before the product.
ROOM_PRIOR_FLOOR = 0.05
_FLOOR = Interval(0.0, 1.0, "left")


def combine_room_priors(
    from_scan: Mapping[str, float] | None,
    from_images: Mapping[str, float] | None,
    *,
    floor: float = ROOM_PRIOR_FLOOR,
) -> dict[str, float] | None:
    """P_N from the scan and P_N from photographs combined into one distribution.

    Parameters
    ----------
    from_scan, from_images : mapping category -> probability, or None
        The two estimates (weights are normalised first; keys are room categories as
        :func:`ontodetect.ontology.room_distribution` accepts them). None: that source
        is not available.
    floor : float in [0, 1)
        Share ε of the uniform distribution mixed into each source before the product,
        so that neither source's zero can veto the other (see the module's docstring).

    Returns
    -------
    dict or None
        Category -> probability over every room category, summing to 1, most likely
        first; the single available source (normalised) when only one is given; None
        when neither is.

    Examples
    --------
    Both sources find an office likely: it is nearly certain.

    >>> both = combine_room_priors({"office": 0.6, "living_room": 0.4},
    ...                            {"office": 0.9, "kitchen": 0.1})
    >>> [(c, round(p, 3)) for c, p in list(both.items())[:2]]
    [('office', 0.998), ('living_room', 0.001)]

    They disagree, each sure of itself: neither zero vetoes the other.

    >>> both = combine_room_priors({"living_room": 1.0}, {"office": 0.9, "kitchen": 0.1})
    >>> [(c, round(p, 2)) for c, p in list(both.items())[:3]]
    [('living_room', 0.49), ('office', 0.44), ('kitchen', 0.05)]
    >>> combine_room_priors(None, {"office": 2, "kitchen": 2})
    {'office': 0.5, 'kitchen': 0.5}
    >>> combine_room_priors(None, None) is None
    True
    """
    floor = check_param("floor", _FLOOR, floor)
    scan = room_distribution(from_scan) if from_scan is not None else None
    images = room_distribution(from_images) if from_images is not None else None
    if scan is None or images is None:
        return scan if scan is not None else images
    cats = list(dict.fromkeys([*room_categories(), *scan, *images]))
    share = floor / len(cats)

    def floored(p: Mapping[str, float], c: str) -> float:
        return (1.0 - floor) * p.get(c, 0.0) + share

    product = {c: floored(scan, c) * floored(images, c) for c in cats}
    total = sum(product.values())
    if total <= 0.0:  # floor 0 and no category in common: nothing to prefer
        return {c: 1.0 / len(cats) for c in cats}
    ranked = sorted(cats, key=lambda c: (-product[c], c))
    return {c: product[c] / total for c in ranked}
