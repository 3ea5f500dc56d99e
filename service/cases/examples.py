"""Examples for the OpenAPI document: requests (JSON and VEDS) and responses (a real
engine result, rounded)."""

from __future__ import annotations

from typing import Any, Final

from models.pulse import haversine, haversine_amplitude_g

__all__ = [
    "EXAMPLE_CASE_LIST",
    "EXAMPLE_CASE_RESULT",
    "EXAMPLE_NOTIFICATIONS",
    "EXAMPLE_STORED_CASE",
    "EXAMPLE_VEDS",
]

#: The moderate tier's words (``models.tiers``), as the examples below carry them.
MODERATE_WORDS: Final[str] = (
    "Vehicle telemetry consistent with severe injury (2021 guideline, moderate risk): "
    "consider a trauma center, which need not be the highest level; EMS judgment and local "
    "protocol decide."
)

#: `POST /v1/cases` answer for the "summary" example notification (the engine as shipped).
EXAMPLE_CASE_RESULT: dict[str, Any] = {
    "case_id": "0b9e3c55-6a4f-4f3e-9a51-2f1f5d0c7e21",
    "event_id": "tsp-7d1c2a90-0001",
    "received_at": "2026-11-23T08:15:31Z",
    "triage": {
        "iss15_plus": True,
        "probability": 0.03996,
        "probability_ci95": [0.03399, 0.04693],
        "threshold": 0.01798,
        "recommendation": "Vehicle telemetry consistent with severe injury (2021 "
        "guideline, moderate risk): consider a trauma center, which need "
        "not be the highest level; EMS judgment and local protocol "
        "decide.",
        "outcome": "ISS15+",
        "model": "field_iss15@3.4.0",
        "operating_point": "sens85",
        "unknown_inputs_range95": [0.02176, 0.04797],
        "knowledge": "adult_measured",
        "tier": "moderate",
        "high_threshold": 0.2,
    },
    "vehicle": {
        "probability": 0.03996,
        "probability_ci95": [0.03237, 0.04676],
        "heldout_auc": 0.8888,
        "outcome": "anyone ISS15+",
        "model": "field_iss15@3.4.0",
        "tier": "moderate",
        "threshold": 0.01798,
        "high_threshold": 0.2,
    },
    "occupants": [
        {
            "seat": "driver",
            "body": "male_50th",
            "impact_mode": "frontal",
            "field_mode": "frontal",
            "impact_angle_deg": 0.0,
            "in_lpm_coverage": True,
            "method": "lpm",
            "iss": {"estimate": 0, "ci95": [0.0, 1.455]},
            "region_ais": {
                "head_neck": 0,
                "face": 0,
                "chest": 0,
                "abdomen": 0,
                "extremities": 0,
                "external": 0,
            },
            "measures": {
                "hic15": 135.5,
                "nij": 0.3377,
                "chest_deflection_mm": 26.34,
                "chest_vc_m_s": 0.08505,
                "chest_a3ms_g": 41.12,
            },
            "measures_ci95": {
                "hic15": [120.3, 182.9],
                "nij": [0.289, 0.4232],
                "chest_deflection_mm": [25.47, 27.28],
                "chest_vc_m_s": [0.07251, 0.09693],
                "chest_a3ms_g": [38.48, 42.61],
            },
            "interval_method": "pce_bootstrap",
            "point_outside_interval": False,
            "probability_uncorrected": 0.08235,
            "probability_zero_load": 0.04633,
            "sensor_inputs": {
                "posture_deg": 5.8,
                "posture_sd_deg": 2.551,
                "seat_track_mm": 0.0,
                "seat_track_sd_mm": 25.51,
            },
            "region_risk": {
                "head": {
                    "probability": 0.01012,
                    "probability_ci95": [0.006843, 0.01496],
                    "ais_level": 3,
                },
                "face": {
                    "probability": 0.006805,
                    "probability_ci95": [0.005197, 0.008905],
                    "ais_level": 2,
                },
                "neck": {
                    "probability": 0.0003542,
                    "probability_ci95": [0.0001936, 0.0006479],
                    "ais_level": 2,
                },
                "thorax": {
                    "probability": 0.03487,
                    "probability_ci95": [0.02467, 0.04907],
                    "ais_level": 3,
                },
                "abdomen": {
                    "probability": 0.005268,
                    "probability_ci95": [0.003638, 0.007621],
                    "ais_level": 3,
                },
                "spine": {
                    "probability": 0.004363,
                    "probability_ci95": [0.002911, 0.006536],
                    "ais_level": 3,
                },
                "upper_extremity": {
                    "probability": 0.008707,
                    "probability_ci95": [0.005115, 0.01478],
                    "ais_level": 3,
                },
                "lower_extremity": {
                    "probability": 0.01992,
                    "probability_ci95": [0.01209, 0.03265],
                    "ais_level": 3,
                },
            },
            "triage": {
                "iss15_plus": True,
                "probability": 0.03996,
                "probability_ci95": [0.03399, 0.04693],
                "threshold": 0.01798,
                "recommendation": "Vehicle telemetry consistent with severe injury "
                "(2021 guideline, moderate risk): consider a "
                "trauma center, which need not be the highest "
                "level; EMS judgment and local protocol decide.",
                "outcome": "ISS15+",
                "model": "field_iss15@3.4.0",
                "operating_point": "sens85",
                "unknown_inputs_range95": [0.02176, 0.04797],
                "knowledge": "adult_measured",
                "tier": "moderate",
                "high_threshold": 0.2,
            },
            "occupant_model": {
                "iss15_plus": False,
                "probability": 0.03777,
                "probability_ci95": [0.03513, 0.04372],
                "threshold": 0.1,
                "recommendation": "No telemetry indication of ISS 15 or "
                "more: destination by EMS field "
                "assessment under local protocol.",
                "outcome": "ISS15+",
                "model": "occupant_models",
                "operating_point": None,
                "unknown_inputs_range95": None,
                "knowledge": None,
                "tier": None,
                "high_threshold": None,
            },
            "baseline": {
                "iss15_plus": True,
                "probability": 0.4722,
                "probability_ci95": [0.2666, 0.6876],
                "threshold": 0.042,
                "recommendation": "Vehicle telemetry consistent with severe "
                "injury (2021 guideline, moderate risk): "
                "consider a trauma center, which need not be "
                "the highest level; EMS judgment and local "
                "protocol decide.",
                "outcome": "police_A+K",
                "model": "nass_logistic",
                "operating_point": None,
                "unknown_inputs_range95": None,
                "knowledge": None,
                "tier": None,
                "high_threshold": None,
            },
        }
    ],
    "pulse": {
        "delta_v_kmh": 56.0,
        "delta_v_longitudinal_kmh": -56.0,
        "delta_v_lateral_kmh": 0.0,
        "pdof_deg": 0.0,
        "peak_accel_g": 31.72,
        "duration_ms": 100.0,
        "haversine": {"amplitude_g": 31.72, "duration_ms": 100.0, "r_squared": 1.0},
        "delta_v_source": "measured",
    },
    "assumptions": [
        {
            "code": "model_year_imputed",
            "message": "occupants[0]: vehicle model year unknown: the field risk models "
            "use 2010 (their latest accident year's median)",
            "occupant": 0,
        },
        {
            "code": "delta_v_measured",
            "message": "occupants[0]: delta-V measured by the vehicle (56.0 km/h): the "
            "field risk models learned reconstructed delta-V, which reads "
            "lower; the probability is the average over the reconstructed "
            "delta-V the measurement model (delta_v_measurement@1.2.0) gives "
            "for it",
            "occupant": 0,
        },
        {
            "code": "inputs_integrated",
            "message": "occupants[0]: stature, mass unknown: the probability is the "
            "average over such occupants of this seat in the field data (the "
            "spread over them 0.0215-0.0476, in `unknown_inputs_range95`)",
            "occupant": 0,
        },
    ],
    "engine_version": "0.2.0",
    "models": {
        "baseline": {
            "version": "1.0.0",
            "sha256": "b670eb94214f8538cb2bf5a286f617204aec2c091e667622dc418cd6b1ac7710",
        },
        "field_model": {
            "version": "3.4.0",
            "sha256": "9ab150a6a2abde1cb2c94310fcff737b6baa39f5f0dc04344edc74407f1af051",
        },
        "delta_v_measurement": {
            "version": "1.2.0",
            "sha256": "47b600b93e2c6483c70b55c175ee3c5de00e84d217d68c0af8f8bd5ee8dccc8a",
        },
        "lpm_parameters:compact_sedan": {
            "version": "compact_sedan",
            "sha256": "323db6162859586c8b689d25989c7ea47c485bca2a83e070da434c306ff5ac75",
        },
        "lpm_code": {
            "version": "0.2.0",
            "sha256": "dbcc944402a64c1f828bd136d690051c708445e1c2f29f2f40896c28d2100787",
        },
        "triage_code": {
            "version": "0.2.0",
            "sha256": "5c92f797feb403293e3c154ab8621410bd774c39b0fb199fa78c14bdad72611c",
        },
        "risk_calibration": {
            "version": "1",
            "sha256": "4811df3c925fe85a84800deb135d25e010ab786df25562441ef01616113e0aa5",
        },
        "surrogates": {
            "version": "6.0.2.0",
            "sha256": "12a879da7cb78f25b7fe5db8c34d496619609babe7813c545240f9572dc4a04b",
        },
        "surrogate_evaluation": {
            "version": "7",
            "sha256": "d4ec27117465c90811900c32d98fb220022f869986c5b0b85fafc1763892451c",
        },
    },
    "timings_ms": {"pulse": 0.179, "occupants": 21.25, "field_model": 1.327, "engine_total": 21.43},
    "stored": True,
    "spooled": False,
}

#: `GET /v1/cases/{case_id}`.
EXAMPLE_STORED_CASE: dict[str, Any] = {
    "case_id": EXAMPLE_CASE_RESULT["case_id"],
    "event_id": EXAMPLE_CASE_RESULT["event_id"],
    "client_name": "metro-psap-telematics",
    "received_at": EXAMPLE_CASE_RESULT["received_at"],
    "stored_at": "2026-11-23T08:15:31.084Z",
    "request_sha256": "5d0b2f9a6c1e4b7d8a3f0e9c2b1a7d6e5f4c3b2a1908f7e6d5c4b3a291807f6e",
    "notification": {"event_id": EXAMPLE_CASE_RESULT["event_id"], "...": "as received"},
    "result": EXAMPLE_CASE_RESULT,
    "models": EXAMPLE_CASE_RESULT["models"],
    "source_format": "json",
    "source_document": None,
    "source_mapping": None,
    "tiers_derived": False,
}

#: `GET /v1/cases`.
EXAMPLE_CASE_LIST: dict[str, Any] = {
    "items": [
        {
            "case_id": EXAMPLE_CASE_RESULT["case_id"],
            "event_id": EXAMPLE_CASE_RESULT["event_id"],
            "client_name": "metro-psap-telematics",
            "received_at": EXAMPLE_CASE_RESULT["received_at"],
            "iss15_plus": EXAMPLE_CASE_RESULT["triage"]["iss15_plus"],
            "tier": EXAMPLE_CASE_RESULT["triage"]["tier"],
            "probability": EXAMPLE_CASE_RESULT["triage"]["probability"],
            "impact_modes": ["frontal"],
        }
    ],
    "next_cursor": "WyIyMDI2LTExLTIzVDA4OjE1OjMxKzAwOjAwIiwgIjBiOWUzYzU1Il0",
}


def _haversine_example(delta_v_kmh: float, duration_ms: float, n: int) -> list[float]:
    """A short frontal haversine pulse for the OpenAPI example (1 kHz)."""
    t_s = [i / 1000.0 for i in range(n)]
    a = haversine(
        t_s, haversine_amplitude_g(delta_v_kmh, duration_ms / 1000.0), duration_ms / 1000.0
    )
    return [round(-float(v), 3) for v in a]


EXAMPLE_NOTIFICATIONS: dict[str, dict[str, Any]] = {
    "summary": {
        "summary": "Frontal crash, summary pulse",
        "description": "56 km/h frontal, belted driver with deployed airbag, posture and "
        "seat position sensed.",
        "value": {
            "event_id": "tsp-7d1c2a90-0001",
            "occurred_at": "2026-11-23T08:15:30Z",
            "vehicle": {"model": "compact_sedan", "drive_side": "left"},
            "crash": {
                "pulse": {"kind": "summary", "delta_v_kmh": 56.0, "pdof_deg": 0.0},
                "multiple_impacts": False,
                "rollover": False,
            },
            "occupants": [
                {
                    "seat": "driver",
                    "body": "male_50th",
                    "age_years": 42,
                    "sex": "male",
                    "belted": True,
                    "frontal_airbag": "deployed",
                    "airbag_fire_time_ms": 15,
                    "pretensioner_fired": True,
                    "posture_lumbar_flexion_deg": 5.8,
                    "seat_track_mm": 0.0,
                }
            ],
        },
    },
    "delta_v": {
        "summary": "Near-side crash, EDR delta-V record",
        "description": "49 CFR 563 record at 10 ms: a left-side impact on a left-hand-drive "
        "car; the driver is on the near side (her side and curtain airbags deployed; the EDR "
        "seat track switch says her seat is forward), the passenger on the far side.",
        "value": {
            "event_id": "tsp-7d1c2a90-0002",
            "occurred_at": "2026-11-23T09:02:11+01:00",
            "vehicle": {"model": "compact_sedan", "drive_side": "left"},
            "crash": {
                "pulse": {
                    "kind": "delta_v",
                    "interval_ms": 10,
                    "longitudinal_kmh": [0, -0.5, -1.2, -1.8, -2.1, -2.2, -2.2, -2.2, -2.2],
                    "lateral_kmh": [0, 6.0, 15.0, 24.0, 29.0, 31.0, 31.5, 31.5, 31.5],
                },
                "multiple_impacts": False,
                "rollover": False,
            },
            "occupants": [
                {
                    "seat": "driver",
                    "stature_cm": 162,
                    "mass_kg": 58,
                    "age_years": 67,
                    "sex": "female",
                    "belted": True,
                    "frontal_airbag": "not_deployed",
                    "side_airbag": "deployed",
                    "seat_track_foremost": True,
                },
                {
                    "seat": "front_passenger",
                    "body": "male_50th",
                    "age_years": 35,
                    "sex": "male",
                    "belted": False,
                    "frontal_airbag": "not_deployed",
                    "side_airbag": "not_deployed",
                },
            ],
        },
    },
    "acceleration": {
        "summary": "Frontal crash, acceleration pulse",
        "description": "Sensor acceleration at 1 kHz, 48 km/h in 90 ms, unbelted passenger "
        "leaning forward, seat moved 40 mm forward.",
        "value": {
            "event_id": "tsp-7d1c2a90-0003",
            "occurred_at": "2026-11-23T10:44:00Z",
            "vehicle": {"model": "compact_sedan", "drive_side": "left"},
            "crash": {
                "pulse": {
                    "kind": "acceleration",
                    "sample_rate_hz": 1000,
                    "longitudinal_g": _haversine_example(48.0, 90.0, 121),
                    "lateral_g": [0.0] * 121,
                },
                "multiple_impacts": False,
                "rollover": False,
            },
            "occupants": [
                {
                    "seat": "front_passenger",
                    "body": "female_5th",
                    "age_years": 29,
                    "sex": "female",
                    "belted": False,
                    "frontal_airbag": "deployed",
                    "posture_lumbar_flexion_deg": 20.0,
                    "seat_track_mm": 40.0,
                }
            ],
        },
    },
}


#: The OpenAPI example of a VEDS body (written for this service in the shape of the
#: RFC 8148 example): a frontal crash at 20 MPH, a belted driver, a deployed airbag.
EXAMPLE_VEDS: Final[dict[str, dict[str, str]]] = {
    "veds_frontal": {
        "summary": "VEDS 3.1, frontal crash in MPH",
        "description": "20 MPH (32.19 km/h) at 12 o'clock; a belted driver whose frontal "
        "airbag deployed. The incident id is the event_id.",
        "value": """<?xml version="1.0" encoding="UTF-8"?>
<veds:AutomatedCrashNotification xmlns:veds="http://www.veds.org/acn/3.1"
    xmlns:nc="http://niem.gov/niem/niem-core/2.0">
  <veds:Crash>
    <nc:ActivityIdentification><nc:IdentificationID>tsp-7d1c2a90-0004</nc:IdentificationID>
    </nc:ActivityIdentification>
    <nc:ActivityDate><nc:DateTime>2026-11-23T08:15:30Z</nc:DateTime></nc:ActivityDate>
    <veds:CrashVehicle>
      <nc:ItemMakeName>Toyota</nc:ItemMakeName>
      <nc:ItemModelName>Yaris</nc:ItemModelName>
      <nc:ItemModelYearDate>2010</nc:ItemModelYearDate>
      <veds:Airbag>
        <veds:AirbagCategoryCode>FRONT</veds:AirbagCategoryCode>
        <veds:AirbagDeployedIndicator>true</veds:AirbagDeployedIndicator>
      </veds:Airbag>
      <veds:VehicleCrashPulse>
        <veds:CrashPulseChangeInVelocityMeasure>
          <nc:MeasurePointValue>20</nc:MeasurePointValue>
          <nc:MeasureUnitText>MPH</nc:MeasureUnitText>
        </veds:CrashPulseChangeInVelocityMeasure>
        <veds:CrashPulsePrincipalDirectionOfForceValue>12</veds:CrashPulsePrincipalDirectionOfForceValue>
        <veds:CrashPulseRolloverQuarterTurnsValue>0</veds:CrashPulseRolloverQuarterTurnsValue>
      </veds:VehicleCrashPulse>
      <veds:VehicleSeat>
        <veds:VehicleSeatLocationCategoryCode>1</veds:VehicleSeatLocationCategoryCode>
        <veds:VehicleSeatOccupiedIndicator>true</veds:VehicleSeatOccupiedIndicator>
        <veds:VehicleSeatbeltFastenedIndicator>true</veds:VehicleSeatbeltFastenedIndicator>
      </veds:VehicleSeat>
    </veds:CrashVehicle>
  </veds:Crash>
</veds:AutomatedCrashNotification>
""",
    }
}
