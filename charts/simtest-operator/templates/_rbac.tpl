{{/* The operator's permissions, one rule per reason. Namespaced rules go into the ClusterRole
     (whole cluster) or into one Role per watched namespace; cluster-scoped reads always go into
     a ClusterRole. Keep docs/install.md ("What the operator may do") in step. */}}

{{- define "simtest-operator.namespacedRules" -}}
# Campaigns are only read (kopf indexes and watches them; the operator writes their status).
- apiGroups: ["simtest.dev"]
  resources: ["testcampaigns"]
  verbs: ["get", "list", "watch"]
# Batches are created (and garbage-collected with their campaign); environments are also
# deleted once their results are folded into the batch.
- apiGroups: ["simtest.dev"]
  resources: ["scenariobatches"]
  verbs: ["get", "list", "watch", "create"]
- apiGroups: ["simtest.dev"]
  resources: ["simenvironments"]
  verbs: ["get", "list", "watch", "create", "delete"]
- apiGroups: ["simtest.dev"]
  resources: ["testcampaigns/status", "scenariobatches/status", "simenvironments/status"]
  verbs: ["patch"]
# Children carry ownerReferences with blockOwnerDeletion, which the
# OwnerReferencesPermissionEnforcement admission plugin allows only with update on finalizers.
- apiGroups: ["simtest.dev"]
  resources: ["testcampaigns/finalizers", "scenariobatches/finalizers", "simenvironments/finalizers"]
  verbs: ["update"]
# Simulator pods: created from the rendered spec, watched for their terminated state, deleted at
# teardown. No exec, no logs, no patch.
- apiGroups: [""]
  resources: ["pods"]
  verbs: ["get", "list", "watch", "create", "delete"]
# The frozen scenario list (created once, read after restarts) and `configMap` scenario sources.
- apiGroups: [""]
  resources: ["configmaps"]
  verbs: ["get", "create"]
# One ServiceAccount per campaign for its simulator pods (no token, no bindings).
- apiGroups: [""]
  resources: ["serviceaccounts"]
  verbs: ["create"]
# Rate-limited events on phase changes.
- apiGroups: [""]
  resources: ["events"]
  verbs: ["create"]
{{- if .Values.rbac.readSecrets }}
# Bearer tokens of `graphql` and `rest` scenario sources (secretRef): single named reads only.
- apiGroups: [""]
  resources: ["secrets"]
  verbs: ["get"]
{{- end }}
# Jobs: the evaluation step (spec.evaluation.offline) and, with provisioner: Helmfile, the
# helmfile sync/destroy Jobs.
- apiGroups: ["batch"]
  resources: ["jobs"]
  verbs: ["get", "list", "watch", "create", "delete"]
# Kueue (spec.execution.queueName): one Workload per campaign asks its LocalQueue for the
# window; watched for the admitted count, deleted when the campaign is done. Harmless without
# Kueue (no such resource to watch).
- apiGroups: ["kueue.x-k8s.io"]
  resources: ["workloads"]
  verbs: ["get", "list", "watch", "create", "delete"]
{{- if .Values.helmfileProvisioner.enabled }}
# provisioner: Helmfile — a Job runs helmfile under a per-campaign ServiceAccount that a
# RoleBinding ties to the provisioner ClusterRole (see "simtest-operator.bindRule").
- apiGroups: ["rbac.authorization.k8s.io"]
  resources: ["rolebindings"]
  verbs: ["create"]
{{- end }}
{{- end }}

{{/* Binding the provisioner ClusterRole needs `bind` on exactly that role (otherwise the API
     server demands that the operator hold every permission it grants). */}}
{{- define "simtest-operator.bindRule" -}}
- apiGroups: ["rbac.authorization.k8s.io"]
  resources: ["clusterroles"]
  verbs: ["bind"]
  resourceNames: [{{ include "simtest-operator.provisionerRoleName" . | quote }}]
{{- end }}

{{- define "simtest-operator.clusterRules" -}}
# Nodes: the simulator slots (simtest.dev/simulator allocatable) bound the in-flight window.
- apiGroups: [""]
  resources: ["nodes"]
  verbs: ["list", "watch"]
# kopf follows the served custom resources through their definitions.
- apiGroups: ["apiextensions.k8s.io"]
  resources: ["customresourcedefinitions"]
  verbs: ["list", "watch"]
{{- end }}
