{{- /* ros2 launch takes parameter files as launch arguments, not --ros-args. */ -}}
{{- define "k8s-ros.args" -}}
{{- $args := list "launch" "planner" "planner.launch.py" }}
{{- range $file, $_ := .Values.params }}
{{- $args = append $args (printf "params_file:=%s/%s" $.Values.paramsMountPath $file) }}
{{- end }}
{{- toYaml $args }}
{{- end }}
