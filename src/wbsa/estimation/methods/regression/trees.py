"""Gradient-boosted trees as plain arrays: fitted with scikit-learn, stored without pickle, evaluated in numpy.

A :class:`TreeEnsemble` holds every tree of a fitted ``HistGradientBoostingRegressor`` (or a binary
``HistGradientBoostingClassifier``), or of a bag of them (:meth:`TreeEnsemble.average`), as concatenated
node arrays, so a model file is numbers only (safe to load from anywhere) and prediction needs no
scikit-learn.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.errors import WbsaError

_FIELDS = ("feature", "threshold", "left", "right", "leaf", "missing_left", "value")


@dataclass(frozen=True)
class TreeEnsemble:
    """Trees of a gradient-boosting model.

    Attributes
    ----------
    feature : (m,) int64
        Split feature of each node (all trees concatenated).
    threshold : (m,) float64
        Go left where ``x[feature] <= threshold``.
    left, right : (m,) int64
        Children, as indices into the concatenated arrays.
    leaf : (m,) bool
    missing_left : (m,) bool
        Where NaN goes.
    value : (m,) float64
        Leaf values (summed over trees; a bag's are divided by its size).
    roots : (t,) int64
        Root node of each tree.
    baseline : float
        Raw prediction before the trees.
    """

    feature: np.ndarray
    threshold: np.ndarray
    left: np.ndarray
    right: np.ndarray
    leaf: np.ndarray
    missing_left: np.ndarray
    value: np.ndarray
    roots: np.ndarray
    baseline: float

    def __repr__(self) -> str:
        return f"TreeEnsemble({len(self.roots)} trees, {len(self.feature)} nodes, baseline {self.baseline:.4g})"

    @classmethod
    def from_sklearn(cls, model) -> "TreeEnsemble":
        """From a fitted ``HistGradientBoostingRegressor`` or binary ``HistGradientBoostingClassifier``.

        Parameters
        ----------
        model : sklearn.ensemble.HistGradientBoostingRegressor or HistGradientBoostingClassifier
            Fitted, single output.
        """
        parts, roots, offset = [], [], 0
        for iteration in model._predictors:
            if len(iteration) != 1:
                raise ValueError("only single-output boosting models can be stored")
            nodes = iteration[0].nodes
            if np.any(nodes["is_categorical"]):
                raise ValueError("categorical splits are not supported")
            parts.append((nodes["feature_idx"].astype(np.int64), nodes["num_threshold"].astype(np.float64),
                          nodes["left"].astype(np.int64) + offset, nodes["right"].astype(np.int64) + offset,
                          nodes["is_leaf"].astype(bool), nodes["missing_go_to_left"].astype(bool),
                          nodes["value"].astype(np.float64)))
            roots.append(offset)
            offset += len(nodes)
        arrays = [np.concatenate([p[i] for p in parts]) for i in range(7)]
        return cls(*arrays, roots=np.asarray(roots, dtype=np.int64),
                   baseline=float(np.ravel(model._baseline_prediction)[0]))

    @classmethod
    def average(cls, ensembles: list["TreeEnsemble"]) -> "TreeEnsemble":
        """One ensemble predicting the mean of the raw predictions of ``ensembles`` (a bag of boosted models).

        Parameters
        ----------
        ensembles : list of TreeEnsemble
            At least one, over the same features.

        Returns
        -------
        TreeEnsemble
            Their trees together, leaf values divided by ``len(ensembles)``, the mean baseline.
        """
        k = len(ensembles)
        if k == 0:
            raise ValueError("TreeEnsemble.average needs at least one ensemble")
        offsets = np.cumsum([0] + [len(e.value) for e in ensembles[:-1]])
        cat = {f: np.concatenate([getattr(e, f) for e in ensembles]) for f in _FIELDS}
        for f in ("left", "right"):
            cat[f] = np.concatenate([getattr(e, f) + o for e, o in zip(ensembles, offsets)])
        cat["value"] = cat["value"] / k
        roots = np.concatenate([e.roots + o for e, o in zip(ensembles, offsets)])
        return cls(*(cat[f] for f in _FIELDS), roots=roots, baseline=float(np.mean([e.baseline for e in ensembles])))

    def predict_raw(self, X: np.ndarray) -> np.ndarray:
        """(n,) float64 raw prediction (a regressor's value; a classifier's log-odds) of (n, d) features.

        Parameters
        ----------
        X : (n, d) float64
            Features; NaN goes the way each split learned for missing values.
        """
        X = np.asarray(X, dtype=np.float64)
        n = X.shape[0]
        node = np.broadcast_to(self.roots, (n, len(self.roots))).copy()
        rows = np.arange(n)[:, None]
        for _ in range(64):
            leaf = self.leaf[node]
            if leaf.all():
                break
            x = X[rows, self.feature[node]]
            go_left = np.where(np.isnan(x), self.missing_left[node], x <= self.threshold[node])
            node = np.where(leaf, node, np.where(go_left, self.left[node], self.right[node]))
        return self.baseline + self.value[node].sum(axis=1)

    def to_arrays(self, prefix: str) -> dict[str, np.ndarray]:
        """The ensemble as named arrays (for ``numpy.savez``).

        Parameters
        ----------
        prefix : str
            Put before every array's name.
        """
        out = {f"{prefix}{f}": getattr(self, f) for f in _FIELDS}
        out[f"{prefix}roots"] = self.roots
        out[f"{prefix}baseline"] = np.array([self.baseline])
        return out

    @classmethod
    def from_arrays(cls, arrays, prefix: str, source: str = "the model") -> "TreeEnsemble":
        """Inverse of :meth:`to_arrays`, checked: every member there, of its kind and length, every node and root
        index inside the arrays, split features not negative.

        Parameters
        ----------
        arrays : mapping of str to array
            A model file's arrays.
        prefix : str
            The prefix :meth:`to_arrays` was given.
        source : str
            The file's name in the messages.

        Raises
        ------
        WbsaError
            One line naming ``source`` (the file) and the member that is wrong.
        """
        def bad(name: str, what: str) -> WbsaError:
            return WbsaError(f"{source}: {prefix}{name} {what}; the model file is damaged, rebuild it")

        got = {}
        for name, kinds in (("feature", "iu"), ("threshold", "f"), ("left", "iu"), ("right", "iu"), ("leaf", "b"),
                            ("missing_left", "b"), ("value", "f"), ("roots", "iu"), ("baseline", "f")):
            if f"{prefix}{name}" not in arrays:
                raise bad(name, "is missing")
            a = np.asarray(arrays[f"{prefix}{name}"])
            if a.ndim != 1 or a.dtype.kind not in kinds:
                raise bad(name, f"is a {a.dtype} array of shape {a.shape}, not a list of "
                                f"{ {'iu': 'integers', 'f': 'numbers', 'b': 'booleans'}[kinds]}")
            got[name] = a
        m = len(got["feature"])
        for name in _FIELDS:
            if len(got[name]) != m:
                raise bad(name, f"has {len(got[name])} entries, not the {m} nodes of {prefix}feature")
        if len(got["baseline"]) != 1 or m == 0 or len(got["roots"]) == 0:
            raise bad("baseline" if len(got["baseline"]) != 1 else "roots", "has the wrong size")
        for name in ("left", "right", "roots"):
            a = got[name] if name == "roots" else got[name][~got["leaf"]]
            if a.size and (a.min() < 0 or a.max() >= m):
                raise bad(name, f"points outside the {m} nodes (index {int(a.min() if a.min() < 0 else a.max())})")
        split = got["feature"][~got["leaf"]]
        if split.size and split.min() < 0:
            raise bad("feature", "holds a negative feature index")
        if not np.all(np.isfinite(got["value"])) or not np.all(np.isfinite(got["baseline"])):
            raise bad("value", "holds numbers that are not finite")
        return cls(*(got[f] for f in _FIELDS), roots=got["roots"],
                   baseline=float(np.asarray(arrays[f"{prefix}baseline"])[0]))
