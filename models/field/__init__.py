"""The field risk model: P(MAIS 3+) of a real occupant from what a notification carries.

Fitted offline on real NASS-CDS crashes (:mod:`models.field.fit`, ``aacn-triage
fit-field``), shipped as a JSON artifact with its checksum and model card
(``docs/field/MODEL_CARD.md``), served with numpy only
(:mod:`models.field.model`). Its probability is the one the service decides on;
the occupant models' answer stays in every response as the physics explanation.
"""
