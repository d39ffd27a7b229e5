//! The Foxglove WebSocket protocol (`foxglove` crate): one channel per topic the node reads,
//! advertised with encoding `cdr` and a `ros2msg` schema (the type's full definition, as
//! rosbag2 writes it into MCAP), carrying the payloads exactly as received (encapsulation
//! header + CDR body), so Foxglove decodes them as it decodes a rosbag2 MCAP.

use std::collections::BTreeMap;
use std::sync::Arc;

use foxglove::{
    ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServerHandle,
};
use metrocell_node::RawMessage;

pub struct FoxgloveBridge {
    context: Arc<Context>,
    server: Option<WebSocketServerHandle>,
    channels: BTreeMap<String, Arc<RawChannel>>,
}

impl FoxgloveBridge {
    /// Start the server on `address:port` (port 0: any free port) in `runtime`.
    pub fn start(
        runtime: &tokio::runtime::Handle,
        address: &str,
        port: u16,
    ) -> Result<FoxgloveBridge, String> {
        let context = Context::new();
        let server = context
            .websocket_server()
            .name("metrocell-dashboard")
            .bind(address, port)
            .tokio_runtime(runtime)
            .start_blocking()
            .map_err(|e| format!("Foxglove WebSocket server on {address}:{port}: {e}"))?;
        Ok(FoxgloveBridge {
            context,
            server: Some(server),
            channels: BTreeMap::new(),
        })
    }

    pub fn port(&self) -> u16 {
        self.server.as_ref().map_or(0, |s| s.port())
    }

    /// Advertise `topic` (`pkg/msg/Type`, full ros2msg definition).
    pub fn advertise(
        &mut self,
        topic: &str,
        ros_type: &str,
        definition: String,
    ) -> Result<(), String> {
        if self.channels.contains_key(topic) {
            return Ok(());
        }
        let channel = ChannelBuilder::new(topic)
            .context(&self.context)
            .message_encoding("cdr")
            .schema(Schema::new(ros_type, "ros2msg", definition.into_bytes()))
            .build_raw()
            .map_err(|e| e.to_string())?;
        self.channels.insert(topic.to_string(), channel);
        Ok(())
    }

    /// Send a received payload to the clients subscribed to its topic, stamped with the
    /// publisher's source time (the receive time when it has none).
    pub fn forward(&self, topic: &str, m: &RawMessage) {
        if let Some(c) = self.channels.get(topic) {
            let log_time = m.source_time_ns.unwrap_or(m.receive_time_ns).max(0) as u64;
            c.log_with_meta(&m.payload, PartialMetadata::with_log_time(log_time));
        }
    }
}

impl Drop for FoxgloveBridge {
    fn drop(&mut self) {
        if let Some(s) = self.server.take() {
            // dropping the shutdown handle aborts the client tasks at once, which is what we want on exit
            drop(s.stop());
        }
    }
}
