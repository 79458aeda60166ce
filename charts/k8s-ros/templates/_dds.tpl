{{/* Generated DDS configuration files; dds.config replaces them with the user's own XML. */}}

{{- define "k8s-ros.cyclonedds" -}}
<?xml version="1.0" encoding="UTF-8"?>
<CycloneDDS xmlns="https://cdds.io/config">
  <Domain Id="any">
    <General>
      <Interfaces>
        {{- if .Values.dds.interface }}
        <NetworkInterface name="{{ .Values.dds.interface }}"/>
        {{- else }}
        <NetworkInterface autodetermine="true"/>
        {{- end }}
      </Interfaces>
      <AllowMulticast>{{ ternary "false" "default" (gt (len .Values.dds.peers) 0) }}</AllowMulticast>
    </General>
    <Discovery>
      <ParticipantIndex>auto</ParticipantIndex>
      <MaxAutoParticipantIndex>120</MaxAutoParticipantIndex>
      {{- with .Values.dds.peers }}
      <Peers>
        {{- range . }}
        <Peer Address="{{ . }}"/>
        {{- end }}
      </Peers>
      {{- end }}
    </Discovery>
  </Domain>
</CycloneDDS>
{{- end }}

{{- define "k8s-ros.fastdds" -}}
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns="http://www.eprosima.com">
  <profiles>
    {{- if .Values.dds.interface }}
    <transport_descriptors>
      <transport_descriptor>
        <transport_id>k8s_ros_udp</transport_id>
        <type>UDPv4</type>
        <interfaceWhiteList>
          <interface>{{ .Values.dds.interface }}</interface>
        </interfaceWhiteList>
      </transport_descriptor>
    </transport_descriptors>
    {{- end }}
    <participant profile_name="k8s_ros" is_default_profile="true">
      <rtps>
        {{- if .Values.dds.interface }}
        <userTransports>
          <transport_id>k8s_ros_udp</transport_id>
        </userTransports>
        <useBuiltinTransports>false</useBuiltinTransports>
        {{- end }}
        {{- with .Values.dds.peers }}
        <builtin>
          <initialPeersList>
            {{- range . }}
            <locator>
              <udpv4>
                <address>{{ . }}</address>
              </udpv4>
            </locator>
            {{- end }}
          </initialPeersList>
        </builtin>
        {{- end }}
      </rtps>
    </participant>
  </profiles>
</dds>
{{- end }}
