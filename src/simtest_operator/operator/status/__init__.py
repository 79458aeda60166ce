"""Status: how the operator reads the three kinds' statuses and words what it writes.

Read side: :mod:`.reading` types a watched status with the same pydantic models the CRDs are
generated from (:mod:`simtest_operator.api.v1alpha1`). Write side: :mod:`.campaignstatus`,
:mod:`.batchstatus` and :mod:`.environmentstatus` build each kind's status patch, from the
shared :mod:`.counting` (counters, progress, final phase), :mod:`.conditions`, :mod:`.records`
(per-scenario results) and :mod:`.patches` (merge patches against the observed wire form).

Import the submodules themselves: this package re-exports nothing, so that importing one of
them (the views need :mod:`.records`) does not load the builders and what they depend on.
"""
