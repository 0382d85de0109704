"""The worked example of docs/environment.md: one chair-like object under different room
priors, its probability P_obj|ont and its cost U (the thesis's Table 4.9 point).

Run as ``python scripts/environment_example.py``; prints a Markdown table.
"""

from __future__ import annotations

import numpy as np

from ontodetect import detect
from ontodetect.config import Config
from ontodetect.labeling import label_costs
from ontodetect.ontology import (
    builtin_ontology,
    class_priors,
    relative_priors,
    with_priors,
)
from ontodetect.synth.rooms import object_scene


def main() -> None:
    onto = builtin_ontology()
    cloud, scene = object_scene(["chair-4leg"], points=30_000, seed=3)
    result = detect(cloud, config=Config().with_overrides(["detect.votes=1"]), room=None)
    chair = next(o.instance_id for o in scene.objects if o.class_name == "chair")
    inst = np.asarray(cloud.fields["instance"])
    k = max(
        range(len(result.segmentation)),
        key=lambda i: np.mean(inst[result.segmentation[i].point_indices] == chair),
    )
    scores, planes = result.scores[k], result.segmentation[k].planes
    rows = [
        ("no prior", {}),
        ("living room, given (Eq. 3.10)", class_priors(onto, "living_room")),
        ("bathroom, given (Eq. 3.10)", class_priors(onto, "bathroom")),
        ("living room, from the scan (relative)", relative_priors(onto, {"living_room": 1.0})),
        ("bathroom, from the scan (relative)", relative_priors(onto, {"bathroom": 1.0})),
    ]
    print("| prior | P_obj chair | P_obj toilet | P_obj\\|ont chair | cost U chair | label |")
    print("|---|---:|---:|---:|---:|---|")
    for name, priors in rows:
        s = with_priors(scores, priors)
        costs = label_costs(s, planes, onto)
        best = min(costs, key=costs.get)
        p_chair = s.probabilities["chair"]
        label = best if onto[best].detect else f"{best} (not reported)"
        print(
            f"| {name} | {priors.get('chair', 1.0):.3f} | {priors.get('toilet', 1.0):.3f} "
            f"| {p_chair:.3f} | {costs['chair']:.3f} | {label} |"
        )


if __name__ == "__main__":
    main()
