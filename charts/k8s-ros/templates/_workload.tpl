{{/* The pod template shared by the Deployment and the Job. */}}

{{- define "k8s-ros.args" -}}
{{- $args := .Values.args }}
{{- if and .Values.ros.appendParamsArgs .Values.params }}
{{- $args = concat $args (list "--ros-args") }}
{{- range $file, $_ := .Values.params }}
{{- $args = concat $args (list "--params-file" (printf "%s/%s" $.Values.paramsMountPath $file)) }}
{{- end }}
{{- end }}
{{- toYaml $args }}
{{- end }}

{{- define "k8s-ros.env" -}}
- name: ROS_DOMAIN_ID
  value: {{ .Values.ros.domainId | quote }}
{{- with .Values.ros.rmw }}
- name: RMW_IMPLEMENTATION
  value: {{ . | quote }}
{{- end }}
- name: ROS_AUTOMATIC_DISCOVERY_RANGE
  value: {{ .Values.ros.discoveryRange | quote }}
- name: ROS_LOCALHOST_ONLY
  value: {{ ternary "1" "0" (eq .Values.ros.discoveryRange "LOCALHOST") | quote }}
- name: HOME
  value: /tmp
- name: ROS_HOME
  value: /tmp/ros
- name: ROS_LOG_DIR
  value: /tmp/ros/log
{{- if .Values.params }}
- name: ROS_PARAMS_DIR
  value: {{ .Values.paramsMountPath | quote }}
{{- end }}
{{- $vendor := include "k8s-ros.ddsVendor" . }}
{{- if eq $vendor "cyclonedds" }}
- name: CYCLONEDDS_URI
  value: {{ printf "file://%s/cyclonedds.xml" .Values.dds.mountPath | quote }}
{{- else if eq $vendor "fastdds" }}
- name: FASTRTPS_DEFAULT_PROFILES_FILE
  value: {{ printf "%s/fastdds.xml" .Values.dds.mountPath | quote }}
- name: FASTDDS_DEFAULT_PROFILES_FILE
  value: {{ printf "%s/fastdds.xml" .Values.dds.mountPath | quote }}
{{- end }}
{{- range $name, $value := .Values.env }}
- name: {{ $name }}
  value: {{ $value | toString | quote }}
{{- end }}
{{- with .Values.extraEnv }}
{{ toYaml . }}
{{- end }}
{{- end }}

{{- define "k8s-ros.container" -}}
name: {{ include "k8s-ros.name" . }}
image: {{ include "k8s-ros.image" . | quote }}
imagePullPolicy: {{ include "k8s-ros.pullPolicy" . }}
{{- with .Values.command }}
command:
  {{- toYaml . | nindent 2 }}
{{- end }}
{{- $args := include "k8s-ros.args" . | fromYamlArray }}
{{- with $args }}
args:
  {{- toYaml . | nindent 2 }}
{{- end }}
env:
  {{- include "k8s-ros.env" . | nindent 2 }}
{{- with .Values.envFrom }}
envFrom:
  {{- toYaml . | nindent 2 }}
{{- end }}
{{- with .Values.ports }}
ports:
  {{- toYaml . | nindent 2 }}
{{- end }}
resources:
  {{- toYaml .Values.resources | nindent 2 }}
securityContext:
  {{- toYaml .Values.securityContext | nindent 2 }}
volumeMounts:
  - name: tmp
    mountPath: /tmp
  {{- if .Values.params }}
  - name: params
    mountPath: {{ .Values.paramsMountPath }}
    readOnly: true
  {{- end }}
  {{- if ne (include "k8s-ros.ddsVendor" .) "none" }}
  - name: dds
    mountPath: {{ .Values.dds.mountPath }}
    readOnly: true
  {{- end }}
  {{- with .Values.extraVolumeMounts }}
  {{- toYaml . | nindent 2 }}
  {{- end }}
{{- end }}

{{- define "k8s-ros.podMetadata" -}}
labels:
  {{- include "k8s-ros.selectorLabels" . | nindent 2 }}
  app.kubernetes.io/component: ros2
  {{- with .Values.podLabels }}
  {{- toYaml . | nindent 2 }}
  {{- end }}
annotations:
  checksum/config: {{ include (print $.Template.BasePath "/configmaps.yaml") . | sha256sum }}
  {{- with .Values.podAnnotations }}
  {{- toYaml . | nindent 2 }}
  {{- end }}
{{- end }}

{{- define "k8s-ros.podSpec" -}}
{{- $container := include "k8s-ros.container" . | fromYaml }}
{{- $container = mergeOverwrite $container (deepCopy .Values.overrides.container) }}
serviceAccountName: {{ include "k8s-ros.serviceAccountName" . }}
automountServiceAccountToken: {{ .Values.serviceAccount.automountToken }}
enableServiceLinks: false
{{- if eq .Values.kind "Job" }}
restartPolicy: Never
{{- end }}
{{- with .Values.imagePullSecrets }}
imagePullSecrets:
  {{- toYaml . | nindent 2 }}
{{- end }}
securityContext:
  {{- toYaml .Values.podSecurityContext | nindent 2 }}
containers:
  - {{- toYaml $container | nindent 4 }}
volumes:
  - name: tmp
    emptyDir: {}
  {{- if .Values.params }}
  - name: params
    configMap:
      name: {{ include "k8s-ros.fullname" . }}-params
  {{- end }}
  {{- if ne (include "k8s-ros.ddsVendor" .) "none" }}
  - name: dds
    configMap:
      name: {{ include "k8s-ros.fullname" . }}-dds
  {{- end }}
  {{- with .Values.extraVolumes }}
  {{- toYaml . | nindent 2 }}
  {{- end }}
{{- with .Values.nodeSelector }}
nodeSelector:
  {{- toYaml . | nindent 2 }}
{{- end }}
{{- with .Values.tolerations }}
tolerations:
  {{- toYaml . | nindent 2 }}
{{- end }}
{{- with .Values.affinity }}
affinity:
  {{- toYaml . | nindent 2 }}
{{- end }}
{{- end }}

{{/* The pod spec after values-level overrides. */}}
{{- define "k8s-ros.finalPodSpec" -}}
{{- $spec := include "k8s-ros.podSpec" . | fromYaml }}
{{- toYaml (mergeOverwrite $spec (deepCopy .Values.overrides.podSpec)) }}
{{- end }}
