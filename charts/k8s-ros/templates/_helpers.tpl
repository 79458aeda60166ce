{{/* Names, labels and the pieces of the workload. Every piece is a named template so a
     repository's wrapper chart can replace one by defining the same name in its own templates/
     (Helm loads a parent chart's templates after its dependencies', so the parent's wins):
       k8s-ros.podMetadata  k8s-ros.podSpec  k8s-ros.container  k8s-ros.env  k8s-ros.args
     Values-level tweaks without templates: overrides.container / overrides.podSpec. */}}

{{- define "k8s-ros.name" -}}
{{- default .Chart.Name .Values.nameOverride | trunc 63 | trimSuffix "-" }}
{{- end }}

{{- define "k8s-ros.fullname" -}}
{{- if .Values.fullnameOverride }}
{{- .Values.fullnameOverride | trunc 52 | trimSuffix "-" }}
{{- else }}
{{- $name := default .Chart.Name .Values.nameOverride }}
{{- if contains $name .Release.Name }}
{{- .Release.Name | trunc 52 | trimSuffix "-" }}
{{- else }}
{{- printf "%s-%s" .Release.Name $name | trunc 52 | trimSuffix "-" }}
{{- end }}
{{- end }}
{{- end }}

{{- define "k8s-ros.selectorLabels" -}}
app.kubernetes.io/name: {{ include "k8s-ros.name" . }}
app.kubernetes.io/instance: {{ .Release.Name }}
{{- end }}

{{- define "k8s-ros.labels" -}}
helm.sh/chart: {{ printf "%s-%s" .Chart.Name .Chart.Version | replace "+" "_" | trunc 63 | trimSuffix "-" }}
{{ include "k8s-ros.selectorLabels" . }}
app.kubernetes.io/version: {{ .Chart.AppVersion | quote }}
app.kubernetes.io/managed-by: {{ .Release.Service }}
app.kubernetes.io/component: ros2
{{- with .Values.labels }}
{{ toYaml . }}
{{- end }}
{{- end }}

{{/* metadata.namespace, labels and ownerReferences shared by every object. */}}
{{- define "k8s-ros.metadata" -}}
namespace: {{ .Release.Namespace }}
labels:
  {{- include "k8s-ros.labels" . | nindent 2 }}
{{- with .Values.ownerReferences }}
ownerReferences:
  {{- toYaml . | nindent 2 }}
{{- end }}
{{- end }}

{{- define "k8s-ros.serviceAccountName" -}}
{{- if .Values.serviceAccount.create }}
{{- default (include "k8s-ros.fullname" .) .Values.serviceAccount.name }}
{{- else }}
{{- default "default" .Values.serviceAccount.name }}
{{- end }}
{{- end }}

{{/* The image reference; `image` may be a "repository:tag" string or an object. */}}
{{- define "k8s-ros.image" -}}
{{- $image := .Values.image }}
{{- if kindIs "string" $image }}
{{- required "image must not be empty" $image }}
{{- else }}
{{- $repository := required "image.repository is required" $image.repository }}
{{- if $image.digest }}
{{- printf "%s@%s" $repository $image.digest }}
{{- else }}
{{- printf "%s:%s" $repository (default .Chart.AppVersion $image.tag) }}
{{- end }}
{{- end }}
{{- end }}

{{- define "k8s-ros.pullPolicy" -}}
{{- if and (kindIs "map" .Values.image) .Values.image.pullPolicy }}
{{- .Values.image.pullPolicy }}
{{- else }}
{{- "IfNotPresent" }}
{{- end }}
{{- end }}

{{/* DDS vendor actually written: "cyclonedds", "fastdds" or "none". */}}
{{- define "k8s-ros.ddsVendor" -}}
{{- $vendor := .Values.dds.vendor }}
{{- if eq $vendor "auto" }}
{{- if eq .Values.ros.rmw "rmw_cyclonedds_cpp" }}cyclonedds
{{- else if eq .Values.ros.rmw "rmw_fastrtps_cpp" }}fastdds
{{- else }}none
{{- end }}
{{- else }}
{{- $vendor }}
{{- end }}
{{- end }}

{{- define "k8s-ros.ddsFile" -}}
{{- if eq (include "k8s-ros.ddsVendor" .) "cyclonedds" }}cyclonedds.xml{{ else }}fastdds.xml{{ end }}
{{- end }}

{{/* One params file's text: strings verbatim, mappings as YAML. */}}
{{- define "k8s-ros.paramsText" -}}
{{- if kindIs "string" . }}
{{- . }}
{{- else }}
{{- toYaml . }}
{{- end }}
{{- end }}
