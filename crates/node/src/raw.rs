//! Raw (already CDR-encoded) publishing and subscribing, for tools that learn the message type
//! only at run time (`metrocell topic echo/pub`, the MCAP recorder and player).
//!
//! A payload is what ROS 2 puts on the wire and rosbag2 stores: the 4-byte encapsulation
//! header (`00 01 00 00` = CDR little-endian) followed by the CDR body. RustDDS handles the
//! header itself, so the adapters here strip it on write and rebuild it on read.

use std::marker::PhantomData;

use futures::StreamExt;
use ros2_client::{Gid, ROSTime};
use rustdds::bytes::Bytes;
use rustdds::no_key::{self, Decode, DefaultDecoder, DeserializerAdapter, SerializerAdapter};
use rustdds::RepresentationIdentifier;

use crate::error::NodeError;

/// An encoded payload with its 4-byte encapsulation header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EncodedPayload(pub Vec<u8>);

/// Encapsulation header of CDR little-endian (XCDR1), as ROS 2 writes it.
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Check a payload's header: must be CDR (XCDR1) little-endian.
pub fn check_payload(payload: &[u8]) -> Result<(), String> {
    if payload.len() < 4 {
        return Err(format!(
            "payload of {} bytes is shorter than the 4-byte encapsulation header",
            payload.len()
        ));
    }
    if payload[0..2] != CDR_LE_HEADER[0..2] {
        return Err(format!(
            "encapsulation {:02x} {:02x} is not CDR little-endian (00 01); only CDR_LE payloads can be published",
            payload[0], payload[1]
        ));
    }
    Ok(())
}

/// Serializer adapter writing the body of an [`EncodedPayload`] as CDR_LE.
pub struct RawCdrLeSerializer;

#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct RawPayloadError(String);

impl SerializerAdapter<EncodedPayload> for RawCdrLeSerializer {
    type Error = RawPayloadError;
    fn output_encoding() -> RepresentationIdentifier {
        RepresentationIdentifier::CDR_LE
    }
    fn to_bytes(value: &EncodedPayload) -> Result<Bytes, RawPayloadError> {
        check_payload(&value.0).map_err(RawPayloadError)?;
        Ok(Bytes::copy_from_slice(&value.0[4..]))
    }
}

/// Deserializer adapter that keeps the bytes: yields header + body for CDR (either byte order).
pub struct RawCdrDeserializer;

static RAW_ENCODINGS: [RepresentationIdentifier; 2] = [
    RepresentationIdentifier::CDR_LE,
    RepresentationIdentifier::CDR_BE,
];

impl DeserializerAdapter<EncodedPayload> for RawCdrDeserializer {
    type Error = RawPayloadError;
    type Decoded = EncodedPayload;
    fn supported_encodings() -> &'static [RepresentationIdentifier] {
        &RAW_ENCODINGS
    }
    fn transform_decoded(decoded: EncodedPayload) -> EncodedPayload {
        decoded
    }
}

/// The decoder object RustDDS needs for async streams.
#[derive(Clone, Copy)]
pub struct RawDecoder(PhantomData<()>);

impl<'de> Decode<'de, EncodedPayload> for RawDecoder {
    type Error = RawPayloadError;
    fn decode_bytes(
        self,
        input: &'de [u8],
        encoding: RepresentationIdentifier,
    ) -> Result<EncodedPayload, RawPayloadError> {
        let id = encoding.to_bytes();
        let mut v = Vec::with_capacity(input.len() + 4);
        // The options field is not passed to adapters; XCDR1 writers set it to zero.
        v.extend_from_slice(&[id[0], id[1], 0, 0]);
        v.extend_from_slice(input);
        Ok(EncodedPayload(v))
    }
}

impl DefaultDecoder<EncodedPayload> for RawCdrDeserializer {
    type Decoder = RawDecoder;
    const DECODER: RawDecoder = RawDecoder(PhantomData);
}

/// Publishes encoded payloads under a ROS type given at run time.
pub struct RawPublisher {
    pub(crate) writer: no_key::DataWriter<EncodedPayload, RawCdrLeSerializer>,
    pub(crate) topic: String,
    pub(crate) ros_type: String,
    /// Last matched-reader count seen in the writer's status events.
    pub(crate) matched: std::cell::Cell<usize>,
}

impl RawPublisher {
    /// Publish a payload (header + CDR body), stamped now.
    pub fn publish(&self, payload: &[u8]) -> Result<(), NodeError> {
        self.publish_stamped(payload, None)
    }

    /// Publish with an explicit DDS source timestamp (nanoseconds since the Unix epoch),
    /// e.g. the recording time when replaying a bag.
    pub fn publish_stamped(
        &self,
        payload: &[u8],
        source_time_ns: Option<i64>,
    ) -> Result<(), NodeError> {
        check_payload(payload).map_err(|message| NodeError::Payload {
            topic: self.topic.clone(),
            message,
        })?;
        let stamp = match source_time_ns {
            Some(ns) => ROSTime::from_nanos(ns).into(),
            None => rustdds::Timestamp::now(),
        };
        self.writer
            .write(EncodedPayload(payload.to_vec()), Some(stamp))
            .map_err(|e| NodeError::Write {
                topic: self.topic.clone(),
                message: format!("{e:?}"),
            })
    }

    pub fn topic(&self) -> &str {
        &self.topic
    }

    pub fn ros_type(&self) -> &str {
        &self.ros_type
    }

    pub fn gid(&self) -> Gid {
        use rustdds::RTPSEntity;
        Gid::from(self.writer.guid())
    }

    /// How many DDS readers currently match this writer (QoS-compatible, same topic and type),
    /// as RustDDS last reported in a PublicationMatched status event.
    pub fn matched_subscriptions(&self) -> usize {
        use rustdds::{DataWriterStatus, StatusEvented};
        while let Some(status) = self.writer.try_recv_status() {
            if let DataWriterStatus::PublicationMatched { current, .. } = status {
                self.matched.set(current.count().max(0) as usize);
            }
        }
        self.matched.get()
    }

    /// Wait until every matched reliable reader has acknowledged every sample written so far, or
    /// `max_wait` passes; true if they did (or none is matched). A writer that goes away with
    /// samples unacknowledged cannot repair them, so a publisher calls this before it exits.
    pub fn wait_for_acknowledgments(&self, max_wait: std::time::Duration) -> bool {
        self.writer
            .wait_for_acknowledgments(max_wait)
            .unwrap_or(false)
    }
}

/// One received raw message.
#[derive(Clone, Debug, PartialEq)]
pub struct RawMessage {
    /// Header + CDR body, as rosbag2 stores it.
    pub payload: Vec<u8>,
    /// DDS source timestamp set by the publisher, nanoseconds since the Unix epoch.
    pub source_time_ns: Option<i64>,
    /// When this process received it, nanoseconds since the Unix epoch.
    pub receive_time_ns: i64,
    /// GID of the publishing DDS writer.
    pub publisher_gid: Gid,
    /// Per-publisher sequence number.
    pub sequence_number: i64,
}

/// Receives payloads of any type on a topic without decoding them.
pub struct RawSubscription {
    pub(crate) reader: no_key::SimpleDataReader<EncodedPayload, RawCdrDeserializer>,
    pub(crate) topic: String,
    pub(crate) ros_type: String,
}

fn to_raw_message(dcc: no_key::DeserializedCacheChange<EncodedPayload>) -> RawMessage {
    let source_time_ns = dcc
        .source_timestamp()
        .and_then(|t| ROSTime::try_from(t).ok())
        .map(|t| t.to_nanos());
    let receive_time_ns = ROSTime::try_from(dcc.receive_instant)
        .map(|t| t.to_nanos())
        .unwrap_or_else(|_| crate::logging::system_time_ns());
    RawMessage {
        publisher_gid: Gid::from(dcc.writer_guid()),
        sequence_number: i64::from(dcc.sequence_number),
        source_time_ns,
        receive_time_ns,
        payload: dcc.into_value().0,
    }
}

impl RawSubscription {
    /// Take one message if one is waiting.
    pub fn take(&self) -> Result<Option<RawMessage>, NodeError> {
        self.reader.drain_read_notifications();
        self.reader
            .try_take_one()
            .map(|o| o.map(to_raw_message))
            .map_err(|e| NodeError::Read {
                topic: self.topic.clone(),
                message: e.to_string(),
            })
    }

    /// Wait for the next message.
    pub async fn next(&self) -> Result<RawMessage, NodeError> {
        let stream = self.reader.as_async_stream();
        futures::pin_mut!(stream);
        match stream.next().await {
            Some(Ok(dcc)) => Ok(to_raw_message(dcc)),
            Some(Err(e)) => Err(NodeError::Read {
                topic: self.topic.clone(),
                message: e.to_string(),
            }),
            None => Err(NodeError::Read {
                topic: self.topic.clone(),
                message: "reader stream ended".into(),
            }),
        }
    }

    pub fn topic(&self) -> &str {
        &self.topic
    }

    pub fn ros_type(&self) -> &str {
        &self.ros_type
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adapters_strip_and_rebuild_the_header() {
        let p = EncodedPayload(vec![0, 1, 0, 0, 5, 0, 0, 0]);
        assert_eq!(
            &RawCdrLeSerializer::to_bytes(&p).unwrap()[..],
            &[5, 0, 0, 0]
        );
        let d = RawDecoder(PhantomData)
            .decode_bytes(&[5, 0, 0, 0], RepresentationIdentifier::CDR_LE)
            .unwrap();
        assert_eq!(d, p);
        assert!(RawCdrLeSerializer::to_bytes(&EncodedPayload(vec![0, 0, 0, 0, 1])).is_err());
        assert!(check_payload(&[0, 1]).unwrap_err().contains("shorter"));
    }
}
