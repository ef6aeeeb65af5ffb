"""A WBSA estimate as a FHIR R4 ``Observation`` a clinical system can store.

The code is LOINC 8277-6 "Body surface area" (component "Body surface", property Area, example unit m2;
checked against LOINC 2.82). The value is in m² as UCUM ``m2``; the prediction interval's bounds are
components (there is no LOINC code for them, so their ``code`` is text); the method is text; every flag is
a ``note`` and makes the status ``preliminary`` instead of ``final``.
"""

from __future__ import annotations

LOINC_SYSTEM = "http://loinc.org"
LOINC_BSA = "8277-6"
LOINC_BSA_DISPLAY = "Body surface area"
UCUM_SYSTEM = "http://unitsofmeasure.org"
CATEGORY_SYSTEM = "http://terminology.hl7.org/CodeSystem/observation-category"


def _quantity(value_m2: float) -> dict:
    return {"value": round(float(value_m2), 4), "unit": "m2", "system": UCUM_SYSTEM, "code": "m2"}


def fhir_observation(estimate, *, patient: str | None = None, effective: str | None = None) -> dict:
    """The estimate as a FHIR R4 Observation resource (a JSON-ready dict).

    Parameters
    ----------
    estimate : wbsa.estimation.Estimate
    patient : str, optional
        A reference such as ``Patient/123`` for ``subject``.
    effective : str, optional
        ISO 8601 date-time of the capture for ``effectiveDateTime``.

    Returns
    -------
    dict
    """
    level = round(100 * estimate.level)
    obs: dict = {
        "resourceType": "Observation",
        "status": "preliminary" if estimate.flags else "final",
        "category": [{"coding": [{"system": CATEGORY_SYSTEM, "code": "exam", "display": "Exam"}]}],
        "code": {"coding": [{"system": LOINC_SYSTEM, "code": LOINC_BSA, "display": LOINC_BSA_DISPLAY}],
                 "text": LOINC_BSA_DISPLAY},
    }
    if patient:
        obs["subject"] = {"reference": patient}
    if effective:
        obs["effectiveDateTime"] = effective
    obs["valueQuantity"] = _quantity(estimate.wbsa_m2)
    obs["method"] = {"text": estimate.method_text()}
    obs["component"] = [
        {"code": {"text": f"Body surface area, lower bound of the {level} % prediction interval"},
         "valueQuantity": _quantity(estimate.wbsa_lo_m2)},
        {"code": {"text": f"Body surface area, upper bound of the {level} % prediction interval"},
         "valueQuantity": _quantity(estimate.wbsa_hi_m2)},
    ]
    if estimate.flags:
        obs["note"] = [{"text": f"{name}: {text}"} for name, text in estimate.flags.items()]
    return obs
