{{/* Names, labels and images shared by every template of the chart. */}}

{{- define "simtest-operator.name" -}}
{{- default .Chart.Name .Values.nameOverride | trunc 63 | trimSuffix "-" }}
{{- end }}

{{/* Resource-name prefix, at most 52 characters so suffixes such as "-helmfile-provisioner"
     still fit in a 63-character label value. */}}
{{- define "simtest-operator.fullname" -}}
{{- if .Values.fullnameOverride }}
{{- .Values.fullnameOverride | trunc 42 | trimSuffix "-" }}
{{- else }}
{{- $name := default .Chart.Name .Values.nameOverride }}
{{- if contains $name .Release.Name }}
{{- .Release.Name | trunc 42 | trimSuffix "-" }}
{{- else }}
{{- printf "%s-%s" .Release.Name $name | trunc 42 | trimSuffix "-" }}
{{- end }}
{{- end }}
{{- end }}

{{- define "simtest-operator.chart" -}}
{{- printf "%s-%s" .Chart.Name .Chart.Version | replace "+" "_" | trunc 63 | trimSuffix "-" }}
{{- end }}

{{- define "simtest-operator.selectorLabels" -}}
app.kubernetes.io/name: {{ include "simtest-operator.name" . }}
app.kubernetes.io/instance: {{ .Release.Name }}
{{- end }}

{{- define "simtest-operator.labels" -}}
helm.sh/chart: {{ include "simtest-operator.chart" . }}
{{ include "simtest-operator.selectorLabels" . }}
app.kubernetes.io/version: {{ .Chart.AppVersion | quote }}
app.kubernetes.io/managed-by: {{ .Release.Service }}
app.kubernetes.io/part-of: simtest
{{- end }}

{{- define "simtest-operator.serviceAccountName" -}}
{{- if .Values.serviceAccount.create }}
{{- default (include "simtest-operator.fullname" .) .Values.serviceAccount.name }}
{{- else }}
{{- required "serviceAccount.name is required when serviceAccount.create is false" .Values.serviceAccount.name }}
{{- end }}
{{- end }}

{{/* ClusterRole the operator binds, per namespace, to the ServiceAccount of its helmfile Jobs. */}}
{{- define "simtest-operator.provisionerRoleName" -}}
{{- printf "%s-helmfile-provisioner" (include "simtest-operator.fullname" .) }}
{{- end }}

{{/* "repository:tag" or "repository@digest"; the tag defaults to the chart's appVersion. */}}
{{- define "simtest-operator.image" -}}
{{- $image := index . 0 }}
{{- $root := index . 1 }}
{{- if $image.digest }}
{{- printf "%s@%s" $image.repository $image.digest }}
{{- else }}
{{- printf "%s:%s" $image.repository (default $root.Chart.AppVersion $image.tag) }}
{{- end }}
{{- end }}

{{/* A string map as `k1=v1,k2=v2`, keys sorted (the operator's SIMTEST_OPERATOR_*_SELECTOR form). */}}
{{- define "simtest-operator.pairs" -}}
{{- $pairs := list -}}
{{- range $key := keys . | sortAlpha -}}
{{- $pairs = append $pairs (printf "%s=%s" $key (index $ $key)) -}}
{{- end -}}
{{- join "," $pairs -}}
{{- end -}}

{{/* The device plugin DaemonSet has its own app.kubernetes.io/name, so that no selector of the
     operator (its Service, its pod anti-affinity) ever matches the plugin pods. */}}
{{- define "simtest-operator.devicePlugin.name" -}}
{{- printf "%s-device-plugin" (include "simtest-operator.fullname" .) }}
{{- end }}

{{- define "simtest-operator.devicePlugin.selectorLabels" -}}
app.kubernetes.io/name: simtest-device-plugin
app.kubernetes.io/instance: {{ .Release.Name }}
{{- end }}

{{- define "simtest-operator.devicePlugin.labels" -}}
helm.sh/chart: {{ include "simtest-operator.chart" . }}
{{ include "simtest-operator.devicePlugin.selectorLabels" . }}
app.kubernetes.io/version: {{ .Chart.AppVersion | quote }}
app.kubernetes.io/managed-by: {{ .Release.Service }}
app.kubernetes.io/part-of: simtest
app.kubernetes.io/component: device-plugin
{{- end }}
