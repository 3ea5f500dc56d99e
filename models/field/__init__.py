"""The field risk models: field-calibrated probabilities from what a notification carries.

The decision's model is the ISS 15+ field risk model (:mod:`models.field.risk_model`,
features :mod:`models.field.risk_features`): P(ISS 15+), P(AIS 3+) per body region and
P(anyone in the vehicle ISS 15+), fitted offline on NASS-CDS 1997-2014
(:mod:`models.offline.field.risk_fit`, ``aacn-triage fit-field``), shipped as a JSON
artifact with its checksums and model card (``docs/field/MODEL_CARD.md``), served with
numpy (each outcome a penalised regression or, where cross-validation chose it, a bag of
boosted trees walked by :mod:`models.field.boosted`). The MAIS 3+ model it replaced
(:mod:`models.field.model`, 2.0.0; 1.0.0 withdrawn) and the first ISS 15+ model (3.0.0)
stay loadable for recall reports (:mod:`models.field.versions`). The occupant models'
answer stays in every response as the physics explanation.
"""
