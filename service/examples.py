"""Example responses for the OpenAPI document (a real engine result, rounded)."""

from __future__ import annotations

from typing import Any

__all__ = ["EXAMPLE_CASE_LIST", "EXAMPLE_CASE_RESULT", "EXAMPLE_STORED_CASE"]

#: `POST /v1/cases` answer for the "summary" example notification (engine 0.1.0).
EXAMPLE_CASE_RESULT: dict[str, Any] = {
    "case_id": "0b9e3c55-6a4f-4f3e-9a51-2f1f5d0c7e21",
    "event_id": "tsp-7d1c2a90-0001",
    "received_at": "2026-11-23T08:15:31Z",
    "triage": {
        "iss15_plus": False,
        "probability": 0.08402,
        "probability_ci95": [0.07272, 0.09643],
        "threshold": 0.1,
        "recommendation": "No telemetry indication of ISS 15 or more: destination by EMS "
        "field assessment under local protocol.",
    },
    "occupants": [
        {
            "seat": "driver",
            "body": "male_50th",
            "impact_mode": "frontal",
            "impact_angle_deg": 0.0,
            "in_lpm_coverage": True,
            "method": "lpm",
            "iss": {"estimate": 0, "ci95": [0.0, 0.0]},
            "region_ais": {
                "head_neck": 0,
                "face": 0,
                "chest": 0,
                "abdomen": 0,
                "extremities": 0,
                "external": 0,
            },
            "measures": {
                "hic15": 149.9,
                "nij": 0.3395,
                "chest_deflection_mm": 31.32,
                "chest_vc_m_s": 0.1199,
                "chest_a3ms_g": 42.16,
            },
            "measures_ci95": {
                "hic15": [142.4, 171.2],
                "nij": [0.2409, 0.4334],
                "chest_deflection_mm": [29.61, 33.46],
                "chest_vc_m_s": [0.1018, 0.1519],
                "chest_a3ms_g": [40.25, 42.16],
            },
            "interval_method": "lpm_sensor_box",
            "point_outside_interval": False,
            "triage": {
                "iss15_plus": False,
                "probability": 0.08402,
                "probability_ci95": [0.07272, 0.09643],
                "threshold": 0.1,
                "recommendation": "No telemetry indication of ISS 15 or more: "
                "destination by EMS field assessment under local "
                "protocol.",
            },
            "baseline": {
                "iss15_plus": True,
                "probability": 0.4722,
                "probability_ci95": [0.2666, 0.6876],
                "threshold": 0.042,
                "recommendation": "Transport to a Level I trauma center: vehicle "
                "telemetry consistent with severe injury (ISS "
                "15 or more likely).",
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
    },
    "assumptions": [],
    "engine_version": "0.1.0",
    "models": {
        "baseline": {
            "version": "1.0.0",
            "sha256": "b670eb94214f8538cb2bf5a286f617204aec2c091e667622dc418cd6b1ac7710",
        },
        "lpm_parameters:compact_sedan": {
            "version": "compact_sedan",
            "sha256": "2071c950bafa1128428115a9863c0d092f10c77e1d34609073057e4b3a585501",
        },
        "lpm_code": {
            "version": "0.1.0",
            "sha256": "82e6c272aa36c58266acabd45f59dbb6dba35fca2f7c0a59d7873dfc304777bd",
        },
    },
    "timings_ms": {"pulse": 0.9, "occupants": 68.2, "engine_total": 69.1},
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
}

#: `GET /v1/cases`.
EXAMPLE_CASE_LIST: dict[str, Any] = {
    "items": [
        {
            "case_id": EXAMPLE_CASE_RESULT["case_id"],
            "event_id": EXAMPLE_CASE_RESULT["event_id"],
            "client_name": "metro-psap-telematics",
            "received_at": EXAMPLE_CASE_RESULT["received_at"],
            "iss15_plus": False,
            "probability": EXAMPLE_CASE_RESULT["triage"]["probability"],
            "impact_modes": ["frontal"],
        }
    ],
    "next_cursor": "WyIyMDI2LTExLTIzVDA4OjE1OjMxKzAwOjAwIiwgIjBiOWUzYzU1Il0",
}
