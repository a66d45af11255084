"""Instance segmentation scores: match predicted objects to true ones by their overlap.

A predicted object and a true object match when their intersection over union (IoU) is at least
``threshold`` (0.5 by default), one to one.  For thresholds above 0.5 the matching is unique (two
objects with IoU > 0.5 with a third would share more than half of it each); for lower ones the
pairs are chosen by the optimal assignment (Hungarian algorithm) on the IoU, as in the StarDist
evaluation.  The Data Science Bowl 2018 score is the ``accuracy`` TP / (TP + FP + FN) averaged over
thresholds 0.5, 0.55, ..., 0.95 (:func:`dsb_score`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["dsb_score", "iou_matrix", "match_instances"]


def iou_matrix(predicted, truth):
    """IoU of every (predicted, true) pair of ids, from two int label images of the same shape.

    Returns
    -------
    iou : ndarray (P, T)
        Row i is the i-th nonzero id of ``predicted`` (in increasing order), column j the j-th of
        ``truth``.
    predicted_ids, true_ids : ndarray
    """
    predicted, truth = np.asarray(predicted), np.asarray(truth)
    if predicted.shape != truth.shape:
        raise ValueError(f"predicted has shape {predicted.shape}, truth has shape {truth.shape}")
    predicted_ids, p_index = np.unique(predicted, return_inverse=True)
    true_ids, t_index = np.unique(truth, return_inverse=True)
    p_index, t_index = p_index.ravel(), t_index.ravel()
    counts = np.zeros((len(predicted_ids), len(true_ids)), dtype=np.int64)
    np.add.at(counts, (p_index, t_index), 1)
    p_keep, t_keep = predicted_ids != 0, true_ids != 0
    p_area, t_area = counts.sum(axis=1), counts.sum(axis=0)
    intersection = counts[np.ix_(p_keep, t_keep)]
    union = p_area[p_keep, None] + t_area[None, t_keep] - intersection
    iou = np.where(union > 0, intersection / np.maximum(union, 1), 0.0)
    return iou, predicted_ids[p_keep], true_ids[t_keep]


def match_instances(predicted, truth, threshold=0.5):
    """Match objects of two label images at an IoU threshold and count hits and misses.

    Parameters
    ----------
    predicted, truth : int ndarray (M, N)
        Label images, 0 = background.
    threshold : float
        A pair matches when its IoU is >= ``threshold`` (in (0, 1]).

    Returns
    -------
    dict
        ``tp, fp, fn`` (counts), ``precision = tp / (tp + fp)``, ``recall = tp / (tp + fn)``,
        ``f1 = 2 tp / (2 tp + fp + fn)``, ``accuracy = tp / (tp + fp + fn)`` and ``mean_iou`` of
        the matched pairs; ``n_predicted``, ``n_true``.
    """
    if not 0.0 < threshold <= 1.0:
        raise ValueError(f"threshold must be in (0, 1], got {threshold!r}")
    iou, predicted_ids, true_ids = iou_matrix(predicted, truth)
    if threshold > 0.5:
        rows, cols = np.nonzero(iou >= threshold)
    else:
        from scipy.optimize import linear_sum_assignment

        rows, cols = linear_sum_assignment(-iou) if iou.size else (np.zeros(0, int), np.zeros(0, int))
        keep = iou[rows, cols] >= threshold
        rows, cols = rows[keep], cols[keep]
    tp = len(rows)
    fp, fn = len(predicted_ids) - tp, len(true_ids) - tp
    return {
        "tp": tp, "fp": fp, "fn": fn,
        "precision": tp / max(tp + fp, 1), "recall": tp / max(tp + fn, 1),
        "f1": 2 * tp / max(2 * tp + fp + fn, 1), "accuracy": tp / max(tp + fp + fn, 1),
        "mean_iou": float(iou[rows, cols].mean()) if tp else 0.0,
        "n_predicted": len(predicted_ids), "n_true": len(true_ids),
    }


def dsb_score(predicted, truth):
    """The Data Science Bowl 2018 score: ``accuracy`` averaged over IoU thresholds 0.5..0.95."""
    return float(np.mean([match_instances(predicted, truth, t)["accuracy"]
                          for t in np.arange(0.5, 1.0, 0.05)]))
